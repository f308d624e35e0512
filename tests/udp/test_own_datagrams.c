/*
 * udp_multicast's own datagrams (ports/linux/udp_multicast.c): multicast loopback gives every datagram the bus sends
 * back to its receiving socket; the kernel drops them there (a socket filter on the sender's port and address), so
 * that none is queued, read and skipped, while every other sender's datagrams arrive: one with the same port number
 * from another address, one from another port. IPv4 and IPv6. Run by netns-run (multicast on lo only).
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "udp_multicast.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

static void ignore_log(void *ctx, const char *line)
{
    (void)ctx;
    (void)line;
}

static void open_bus(udp_multicast_t *u, const char *spec)
{
    udp_multicast_config_t cfg;
    char err[256];
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, udp_multicast_parse(spec, &cfg, err, sizeof err), err);
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, udp_multicast_open(u, &cfg, "test", ignore_log, NULL, err, sizeof err), err);
}

/* A python-can datagram of CAN-ID id from a socket bound to from (port 0: any), to the bus's group. */
static void send_foreign(const udp_multicast_t *u, const struct sockaddr_storage *from, socklen_t from_len, uint32_t id)
{
    const int fd = socket(u->cfg.group.ss_family, SOCK_DGRAM, 0);
    TEST_ASSERT_TRUE(fd >= 0);
    const unsigned char loop = 1U;
    const int on = 1;
    if (u->cfg.group.ss_family == AF_INET) {
        TEST_ASSERT_EQUAL_INT(0, setsockopt(fd, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop));
    } else {
        TEST_ASSERT_EQUAL_INT(0, setsockopt(fd, IPPROTO_IPV6, IPV6_MULTICAST_LOOP, &on, sizeof on));
    }
    TEST_ASSERT_EQUAL_INT(0, bind(fd, (const struct sockaddr *)from, from_len));
    co_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = 1U;
    f.data[0] = 0x5AU;
    uint8_t d[256];
    const size_t n = udp_datagram_encode(&f, 1.0, d, sizeof d);
    TEST_ASSERT_TRUE(n > 0U);
    TEST_ASSERT_EQUAL_INT((int)n, (int)sendto(fd, d, n, 0, (const struct sockaddr *)&u->cfg.group, u->cfg.group_len));
    (void)close(fd);
}

/* The same from a raw socket (netns-run's user namespace has CAP_NET_RAW in its network namespace): a datagram with
 * the given IPv4 source address and port, which no local UDP socket could be bound to while the bus's sending socket
 * holds the port on every address. */
static void send_raw_ipv4(const udp_multicast_t *u, uint32_t src_addr, uint16_t src_port, uint32_t id)
{
    const int fd = socket(AF_INET, SOCK_RAW, IPPROTO_RAW); /* IP_HDRINCL: the header is ours */
    TEST_ASSERT_TRUE_MESSAGE(fd >= 0, "no raw socket: run inside tests/udp/netns-run");
    co_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = 1U;
    uint8_t p[300];
    memset(p, 0, 28U);
    const size_t n = udp_datagram_encode(&f, 1.0, &p[28], sizeof p - 28U);
    TEST_ASSERT_TRUE(n > 0U);
    const struct sockaddr_in *g = (const struct sockaddr_in *)&u->cfg.group;
    p[0] = 0x45U; /* IPv4, 20 bytes of header; the kernel fills in the total length, the ID and the checksum */
    p[8] = 1U;    /* TTL */
    p[9] = IPPROTO_UDP;
    memcpy(&p[12], &src_addr, 4U);
    memcpy(&p[16], &g->sin_addr, 4U);
    memcpy(&p[20], &src_port, 2U);
    memcpy(&p[22], &g->sin_port, 2U);
    p[24] = (uint8_t)((8U + n) >> 8);
    p[25] = (uint8_t)(8U + n); /* UDP length; checksum 0: none */
    TEST_ASSERT_EQUAL_INT((int)(28U + n), (int)sendto(fd, p, 28U + n, 0, (const struct sockaddr *)g, sizeof *g));
    (void)close(fd);
}

/* Reads for up to a second, until want frames came; returns how many, their CAN-IDs summed into id_sum. */
static unsigned read_frames(udp_multicast_t *u, unsigned want, uint32_t *id_sum)
{
    unsigned got = 0U;
    *id_sum = 0U;
    struct timespec start;
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &start);
    do {
        struct pollfd p = {u->rx_fd, POLLIN, 0};
        (void)poll(&p, 1U, 50);
        co_frame_t f;
        while (udp_multicast_read(u, &f, 0U) == 1) {
            got++;
            *id_sum += f.id;
        }
        clock_gettime(CLOCK_MONOTONIC, &t);
    } while (got < want && (t.tv_sec - start.tv_sec) * 1000000000L + (t.tv_nsec - start.tv_nsec) < 1000000000L);
    /* and a little longer: nothing more may come (the own datagrams would be late ones) */
    struct pollfd p = {u->rx_fd, POLLIN, 0};
    (void)poll(&p, 1U, 100);
    co_frame_t f;
    while (udp_multicast_read(u, &f, 0U) == 1) {
        got++;
    }
    return got;
}

static void send_own(udp_multicast_t *u, unsigned count)
{
    co_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = 0x181U;
    f.len = 2U;
    for (unsigned i = 0U; i < count; i++) {
        TEST_ASSERT_EQUAL_INT(CO_OK, udp_multicast_send(u, &f));
    }
    udp_multicast_flush(u); /* as the end of a pass does */
}

static void test_ipv4_own_datagrams_are_dropped_by_the_kernel_others_arrive(void)
{
    udp_multicast_t u;
    open_bus(&u, ":239.74.165.7:43207,ttl=0");
    TEST_ASSERT_TRUE(u.rx_own_filtered);
    TEST_ASSERT_EQUAL_INT(AF_INET, u.self.ss_family);
    send_own(&u, 50U);
    /* the sender's port from another address (lo has 127.0.0.0/8), then any port from the same address; and the
     * sender's address and port again, as another process could never send (the filter's own test) */
    const struct sockaddr_in *self = (const struct sockaddr_in *)&u.self;
    const uint32_t other_addr = self->sin_addr.s_addr == htonl(0x7F000002U) ? htonl(0x7F000003U) : htonl(0x7F000002U);
    send_raw_ipv4(&u, other_addr, self->sin_port, 0x601U);
    send_raw_ipv4(&u, self->sin_addr.s_addr, self->sin_port, 0x604U);
    struct sockaddr_storage other_port;
    memcpy(&other_port, &u.self, sizeof other_port);
    ((struct sockaddr_in *)&other_port)->sin_port = 0U;
    send_foreign(&u, &other_port, sizeof(struct sockaddr_in), 0x602U);
    uint32_t ids = 0U;
    TEST_ASSERT_EQUAL_UINT(2U, read_frames(&u, 2U, &ids));
    TEST_ASSERT_EQUAL_UINT32(0x601U + 0x602U, ids);
    TEST_ASSERT_EQUAL_UINT32(0U, (uint32_t)u.rx_own); /* none queued, read and skipped */
    TEST_ASSERT_EQUAL_UINT32(50U, (uint32_t)u.tx_frames);
    /* the kernel counts the 50 as drops: not losses; the forged one, which this bus never sent, is one */
    TEST_ASSERT_EQUAL_UINT32(1U, (uint32_t)u.rx_dropped);
    udp_multicast_close(&u);
}

static void test_ipv6_own_datagrams_are_dropped_by_the_kernel_others_arrive(void)
{
    udp_multicast_t u;
    open_bus(&u, ":[ff15::7:1]:43208,ttl=0");
    TEST_ASSERT_TRUE(u.rx_own_filtered);
    TEST_ASSERT_EQUAL_INT(AF_INET6, u.self.ss_family);
    send_own(&u, 50U);
    struct sockaddr_storage other_port;
    memcpy(&other_port, &u.self, sizeof other_port);
    ((struct sockaddr_in6 *)&other_port)->sin6_port = 0U;
    send_foreign(&u, &other_port, sizeof(struct sockaddr_in6), 0x603U);
    uint32_t ids = 0U;
    TEST_ASSERT_EQUAL_UINT(1U, read_frames(&u, 1U, &ids));
    TEST_ASSERT_EQUAL_UINT32(0x603U, ids);
    TEST_ASSERT_EQUAL_UINT32(0U, (uint32_t)u.rx_own);
    TEST_ASSERT_EQUAL_UINT32(0U, (uint32_t)u.rx_dropped);
    udp_multicast_close(&u);
}

/* Datagrams the full receive buffer dropped are still counted as lost, the own ones the filter refused are not. */
static void test_datagrams_lost_to_a_full_receive_buffer_are_counted_and_only_they(void)
{
    udp_multicast_t u;
    open_bus(&u, ":239.74.165.8:43210,ttl=0");
    const int tiny = 1; /* the kernel's least: a few datagrams */
    TEST_ASSERT_EQUAL_INT(0, setsockopt(u.rx_fd, SOL_SOCKET, SO_RCVBUF, &tiny, sizeof tiny));
    send_own(&u, 50U);
    struct sockaddr_storage other_port;
    memcpy(&other_port, &u.self, sizeof other_port);
    ((struct sockaddr_in *)&other_port)->sin_port = 0U;
    for (unsigned i = 0U; i < 40U; i++) {
        send_foreign(&u, &other_port, sizeof(struct sockaddr_in), 0x100U + i); /* nobody reads: most are dropped */
    }
    uint32_t ids = 0U;
    const unsigned first = read_frames(&u, 40U, &ids);
    TEST_ASSERT_TRUE(first > 0U && first < 40U);
    send_own(&u, 50U);
    /* a drop is told with the next datagram queued after it */
    send_foreign(&u, &other_port, sizeof(struct sockaddr_in), 0x200U);
    const unsigned last = read_frames(&u, 1U, &ids);
    TEST_ASSERT_EQUAL_UINT(1U, last);
    TEST_ASSERT_EQUAL_UINT32(41U - first - last, (uint32_t)u.rx_dropped);
    TEST_ASSERT_EQUAL_UINT32(100U, (uint32_t)u.tx_frames);
    udp_multicast_close(&u);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_ipv4_own_datagrams_are_dropped_by_the_kernel_others_arrive);
    RUN_TEST(test_ipv6_own_datagrams_are_dropped_by_the_kernel_others_arrive);
    RUN_TEST(test_datagrams_lost_to_a_full_receive_buffer_are_counted_and_only_they);
    return UNITY_END();
}
