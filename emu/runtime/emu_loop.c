/* The main loop: see emu_loop.h. */
#define _GNU_SOURCE /* ppoll, PATH_MAX and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_loop.h"

#include <errno.h>
#include <poll.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "runtime/emu_bus.h"
#include "control/emu_commands.h"
#include "control/emu_control.h"
#include "runtime/emu_output.h"
#include "scripts/emu_script.h"
#include "control/emu_socket.h"
#include "socketcand/emu_socketcand.h"
#include "web/emu_web.h"
#include "nvm_writer.h"

/* Control sockets listening or connected: only then has a pass their flushing, polling and servicing to do. */
static bool sockets_in_use(const emu_sockets_t *k)
{
    return k->unix_fd >= 0 || k->tcp_fd >= 0 || k->n_clients > 0U;
}

int loop_run(emu_t *emu, const volatile sig_atomic_t *stop)
{
    /* each bus's socket, stdin, stdout and stderr when output waits, the control listeners and clients, the web */
    /* and the socketcand listener and clients, the web's WebSockets */
    struct pollfd pfd[MAX_BUSES + 3 + 2 + MAX_CLIENTS + 1 + 1 + SOCKETCAND_CLIENTS_MAX + WEB_SOCKETS_MAX];
    for (size_t i = 0U; i < emu->n_buses; i++) {
        pfd[i].revents = 0; /* nothing woke the buses before the first pass */
    }
    /* One clock read per wake-up serves its commands, frames and nodes; it is read again where a pass did work of
     * unknown length (commands, sessions, a flood of frames) and before sleeping, so that the sleep ends at the
     * deadline and not late by this pass's work. */
    co_time_us_t now = socketcan_now_us();
    co_time_us_t next = CO_NEVER; /* the earliest deadline the last pass found: a flood's reading stops there */
    /* where the last poll put them */
    nfds_t stdin_index = 0U, sockets_index = 0U, socketcand_index = 0U, web_index = 0U, nfds = 0U;
    const bool alone = emu->n_buses == 1U && !emu->control.open && !sockets_in_use(&emu->sockets) &&
                       emu->web.daemon == NULL && !socketcand_active(&emu->socketcand) &&
                       script_next_at(&emu->script) == CO_NEVER;
    while (!emu->quit && *stop == 0) {
        if (alone) {
            if (bus_run_alone(emu, stop, &now, &next, pfd[0].revents) != 0) {
                return 1;
            }
            pfd[0].revents = 0; /* its last wake-up is served */
            if (emu->quit || *stop != 0) {
                break;
            }
        }
        /* What woke the loop besides the buses: work of unknown length, the clock is read again after it. */
        bool commands = false;
        if (stdin_index != 0U && (pfd[stdin_index].revents & (POLLIN | POLLHUP | POLLERR)) != 0) {
            control_read(emu);
            commands = true;
        }
        const bool sockets = sockets_in_use(&emu->sockets);
        if (sockets && socketcand_index > sockets_index) {
            sockets_service(emu, &emu->sockets, &pfd[sockets_index], socketcand_index - sockets_index);
            commands = true;
        }
        if (emu->web.daemon != NULL && nfds > 0U) {
            web_service(emu, &emu->web, &pfd[web_index], nfds - web_index, now);
            commands = true;
        }
        char line[COMMAND_LINE_MAX + 1];
        /* quit ends the run at once: a script line due at the same time after it must not run (a save there stored).
         * At most SCRIPT_LINES_PER_PASS a pass: the rest of a burst runs in the next passes (their time has come,
         * so the poll does not wait), with the nodes' turns and the replies' writing between (thousands of lines
         * due at once held every heartbeat and filled the replies' buffer until lines were dropped). */
        for (unsigned k = 0U; k < SCRIPT_LINES_PER_PASS && !emu->quit &&
                              script_next_at(&emu->script) <= now - emu->start &&
                              script_take_due(&emu->script, now - emu->start, line, sizeof line);
             k++) {
            run_command(emu, line, &output_stdout_replies);
            commands = true;
        }
        /* The sessions' waiting lines and streamed answers, within the pass's budget and never past the nodes'
         * earliest deadline (the first unit always runs): many busy clients cannot hold the loop (emu_session.h). */
        bool sessions_pending = false;
        if (emu->n_sessions > 0U) {
            const co_time_us_t t = socketcan_now_us();
            const co_time_us_t budget_end = t + SESSION_PASS_BUDGET_US;
            sessions_pending = sessions_work(emu, next < budget_end ? next : budget_end);
            commands = true;
        }
        /* The socketcand clients' frames, within their own bounds and never past the nodes' earliest deadline (the
         * first always runs): the nodes take them in this pass. */
        if (socketcand_active(&emu->socketcand)) {
            sessions_pending = socketcand_service(emu, &emu->socketcand, &pfd[socketcand_index],
                                                  web_index - socketcand_index, next) || sessions_pending;
            commands = true;
        }
        if (commands) {
            now = socketcan_now_us(); /* the nodes run at the time after the commands, which may have taken long */
        }
        const co_time_us_t due = next;
        next = CO_NEVER;
        for (size_t i = 0U; i < emu->n_buses; i++) {
            emu_bus_t *b = emu->buses[i];
            bool tx_pending = false;
            const co_time_us_t t = bus_pass(b, &now, pfd[i].revents, due, &tx_pending);
            next = t < next ? t : next;
            pfd[i].fd = can_channel_fd(&b->can); /* -1 while the interface is gone, on a virtual bus: poll ignores it */
            pfd[i].events = can_channel_poll_events(&b->can, tx_pending); /* no POLLOUT after ENOBUFS: it would spin */
            pfd[i].revents = 0;
        }
        nfds = (nfds_t)emu->n_buses;
        /* The NVM files' background commits the kernel finished: their files closed, a blob waiting for one started.
         * Nothing in flight (nearly always): one counter read, no system call. */
        nvm_writer_poll();
        const co_time_us_t script_at = script_next_at(&emu->script);
        if (script_at != CO_NEVER && emu->start + script_at < next) {
            next = emu->start + script_at;
        }
        /* what this pass logged and replied, as far as the readers take it; POLLOUT wakes the loop to write more */
        if (output_flush()) {
            nfds += output_poll_fds(&pfd[nfds]);
        }
        stdin_index = emu->control.open ? nfds : 0U;
        if (emu->control.open) {
            pfd[nfds].fd = STDIN_FILENO;
            pfd[nfds].events = POLLIN;
            pfd[nfds].revents = 0;
            nfds++;
        }
        sockets_index = nfds;
        if (sockets) {
            sockets_tidy(emu, &emu->sockets);
            nfds += sockets_poll_fds(&emu->sockets, &pfd[nfds], (nfds_t)(sizeof pfd / sizeof pfd[0]) - nfds - 1U);
        }
        now = socketcan_now_us();
        socketcand_index = nfds;
        if (socketcand_active(&emu->socketcand)) { /* what the buses' pass gave its clients leaves here */
            nfds += socketcand_poll_fds(emu, &emu->socketcand, &pfd[nfds], (nfds_t)(sizeof pfd / sizeof pfd[0]) - nfds - 1U,
                                        now, &next);
        }
        web_index = nfds;
        if (emu->web.daemon != NULL) { /* without --web a pass pays for neither call */
            nfds += web_poll_fds(&emu->web, &pfd[web_index], now, &next);
        }
        if (emu->quit || *stop != 0) {
            break; /* a quit this pass took (stdin, a session, a script) ends the run now, not after the next sleep */
        }
        struct timespec ts;
        /* work left for the sessions: no sleep, the next pass goes on with it after the nodes' turn */
        const int ready = ppoll(pfd, nfds, emu_poll_timeout(sessions_pending ? now : next, now, &ts), NULL);
        if (ready < 0) {
            if (errno != EINTR) {
                output_error("poll: %s", strerror(errno));
                return 1;
            }
            for (nfds_t i = 0U; i < nfds; i++) {
                pfd[i].revents = 0; /* a signal: nothing is ready */
            }
        }
        now = socketcan_now_us();
    }
    return 0;
}
