/*
 * A udp_multicast bus's sending side (ports/linux/udp_multicast_tx.c): the frames of a pass wait in a batch and leave
 * together (sendmmsg) when the pass ends, in the order sent; a socket whose buffer is full keeps the batch (POLLOUT
 * then tells when to go on) and refuses a frame only when the batch is full too (CO_ERR_BUSY: the core retries it);
 * a datagram the socket refuses for good is lost alone. sendmmsg is wrapped (-Wl,--wrap=sendmmsg): the test says how
 * many datagrams the "socket buffer" takes, the rest goes to the real call. Run by netns-run (multicast on lo only).
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "udp_multicast.h"
#include "unity.h"

#define UNLIMITED (-1)
static int room = UNLIMITED; /* datagrams the socket takes before it answers EAGAIN; UNLIMITED: all */
static int fail_errno;       /* the next call fails with this for its first datagram (0: none) */
static unsigned calls;

int __real_sendmmsg(int fd, struct mmsghdr *msgs, unsigned vlen, int flags);
int __wrap_sendmmsg(int fd, struct mmsghdr *msgs, unsigned vlen, int flags);
int __wrap_sendmmsg(int fd, struct mmsghdr *msgs, unsigned vlen, int flags)
{
    calls++;
    if (fail_errno != 0) {
        errno = fail_errno;
        fail_errno = 0;
        return -1;
    }
    if (room == 0) {
        errno = EAGAIN;
        return -1;
    }
    if (room != UNLIMITED && vlen > (unsigned)room) {
        vlen = (unsigned)room;
    }
    const int n = __real_sendmmsg(fd, msgs, vlen, flags);
    if (n > 0 && room != UNLIMITED) {
        room -= n;
    }
    return n;
}

static udp_multicast_t u;
static int listener = -1;

static void ignore_log(void *ctx, const char *line)
{
    (void)ctx;
    (void)line;
}

void setUp(void)
{
    room = UNLIMITED;
    fail_errno = 0;
    calls = 0U;
    udp_multicast_config_t cfg;
    char err[256];
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, udp_multicast_parse(":239.74.165.9:43209,ttl=0", &cfg, err, sizeof err), err);
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, udp_multicast_open(&u, &cfg, "test", ignore_log, NULL, err, sizeof err), err);
    listener = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK, 0);
    const int on = 1;
    (void)setsockopt(listener, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    (void)setsockopt(listener, SOL_SOCKET, SO_REUSEPORT, &on, sizeof on);
    TEST_ASSERT_EQUAL_INT(0, bind(listener, (const struct sockaddr *)&cfg.group, cfg.group_len));
    struct ip_mreqn join;
    memset(&join, 0, sizeof join);
    join.imr_multiaddr = ((const struct sockaddr_in *)&cfg.group)->sin_addr;
    join.imr_ifindex = 1;
    TEST_ASSERT_EQUAL_INT(0, setsockopt(listener, IPPROTO_IP, IP_ADD_MEMBERSHIP, &join, sizeof join));
}

void tearDown(void)
{
    room = UNLIMITED;
    udp_multicast_close(&u);
    (void)close(listener);
}

static co_status_t send_id(uint32_t id)
{
    co_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = 1U;
    f.data[0] = (uint8_t)id;
    return udp_multicast_send(&u, &f);
}

/* What the listener got within wait_ms (then until quiet): CAN-IDs in order of arrival. */
static unsigned heard(uint32_t *ids, unsigned max, int wait_ms)
{
    unsigned n = 0U;
    struct pollfd p = {listener, POLLIN, 0};
    while (poll(&p, 1U, wait_ms) > 0) {
        uint8_t d[512];
        ssize_t r;
        while ((r = recv(listener, d, sizeof d, 0)) > 0) {
            co_frame_t f;
            TEST_ASSERT_EQUAL_INT(UDP_DATAGRAM_FRAME, udp_datagram_decode(d, (size_t)r, &f, NULL, 0U));
            if (n < max) {
                ids[n] = f.id;
            }
            n++;
        }
        wait_ms = 50;
    }
    return n;
}

static void assert_in_order(const uint32_t *ids, unsigned n, uint32_t first)
{
    for (unsigned i = 0U; i < n; i++) {
        TEST_ASSERT_EQUAL_HEX32(first + i, ids[i]);
    }
}

static void test_a_passes_frames_leave_together_when_it_ends_in_order(void)
{
    uint32_t ids[300];
    for (uint32_t i = 0U; i < 10U; i++) {
        TEST_ASSERT_EQUAL_INT(CO_OK, send_id(0x100U + i));
    }
    TEST_ASSERT_EQUAL_UINT(0U, heard(ids, 300U, 50)); /* not yet: the pass has not ended */
    TEST_ASSERT_EQUAL_UINT(0U, calls);
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, udp_multicast_tx_service(&u, 1000U)); /* the end of the pass */
    TEST_ASSERT_EQUAL_UINT(1U, calls);                                        /* one system call */
    TEST_ASSERT_EQUAL_UINT(10U, heard(ids, 300U, 500));
    assert_in_order(ids, 10U, 0x100U);
    /* more than a batch in one pass: a full batch is sent as the next frame comes */
    for (uint32_t i = 0U; i < 200U; i++) {
        TEST_ASSERT_EQUAL_INT(CO_OK, send_id(0x200U + i));
    }
    (void)udp_multicast_tx_service(&u, 2000U);
    TEST_ASSERT_EQUAL_UINT(200U, heard(ids, 300U, 500));
    assert_in_order(ids, 200U, 0x200U);
    TEST_ASSERT_EQUAL_UINT32(210U, (uint32_t)u.tx_frames);
}

static void test_a_full_socket_buffer_keeps_the_batch_and_refuses_only_when_it_is_full(void)
{
    uint32_t ids[100];
    room = 0;
    for (uint32_t i = 0U; i < UDP_MULTICAST_TX_BATCH; i++) {
        TEST_ASSERT_EQUAL_INT(CO_OK, send_id(0x300U + i));
    }
    TEST_ASSERT_EQUAL_INT(CO_ERR_BUSY, send_id(0x300U + UDP_MULTICAST_TX_BATCH)); /* the core keeps it */
    TEST_ASSERT_TRUE(udp_multicast_poll_out(&u));                                  /* POLLOUT tells when */
    room = 10;
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, udp_multicast_tx_service(&u, 1000U)); /* 10 went; POLLOUT again, no timer */
    TEST_ASSERT_TRUE(udp_multicast_poll_out(&u));
    TEST_ASSERT_EQUAL_INT(CO_OK, send_id(0x300U + UDP_MULTICAST_TX_BATCH)); /* the core's retry: room now */
    room = UNLIMITED;
    (void)udp_multicast_tx_service(&u, 2000U);
    TEST_ASSERT_FALSE(udp_multicast_poll_out(&u));
    TEST_ASSERT_EQUAL_UINT(UDP_MULTICAST_TX_BATCH + 1U, heard(ids, 100U, 500)); /* none lost, none twice */
    assert_in_order(ids, UDP_MULTICAST_TX_BATCH + 1U, 0x300U);
    TEST_ASSERT_EQUAL_UINT32(0U, (uint32_t)u.tx_lost);
}

/* ENOBUFS (the device's queue) is not reported by POLLOUT: the service asks to run again a little later. */
static void test_enobufs_is_retried_by_the_clock(void)
{
    uint32_t ids[10];
    TEST_ASSERT_EQUAL_INT(CO_OK, send_id(0x400U));
    fail_errno = ENOBUFS;
    TEST_ASSERT_EQUAL_UINT64(5000U + UDP_MULTICAST_TX_RETRY_US, udp_multicast_tx_service(&u, 5000U));
    TEST_ASSERT_FALSE(udp_multicast_poll_out(&u));
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, udp_multicast_tx_service(&u, 6000U));
    TEST_ASSERT_EQUAL_UINT(1U, heard(ids, 10U, 500));
    TEST_ASSERT_EQUAL_HEX32(0x400U, ids[0]);
}

static void test_a_datagram_refused_for_good_is_lost_alone(void)
{
    uint32_t ids[10];
    for (uint32_t i = 0U; i < 5U; i++) {
        TEST_ASSERT_EQUAL_INT(CO_OK, send_id(0x500U + i));
    }
    fail_errno = ENETUNREACH; /* for the first datagram of the batch */
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, udp_multicast_tx_service(&u, 1000U));
    TEST_ASSERT_EQUAL_UINT32(1U, (uint32_t)u.tx_lost);
    TEST_ASSERT_EQUAL_UINT(4U, heard(ids, 10U, 500));
    assert_in_order(ids, 4U, 0x501U);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_a_passes_frames_leave_together_when_it_ends_in_order);
    RUN_TEST(test_a_full_socket_buffer_keeps_the_batch_and_refuses_only_when_it_is_full);
    RUN_TEST(test_enobufs_is_retried_by_the_clock);
    RUN_TEST(test_a_datagram_refused_for_good_is_lost_alone);
    return UNITY_END();
}
