/* Segmented SDO transfer (the option a device profile switches on, e.g. for Bürkert strings). */
#include <string.h>

#include "fixture.h"

void setUp(void)
{
    fx_start(5U, CO_OPT_SDO_SEGMENTED);
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

#define SDO(...)                                                                          \
    do {                                                                                  \
        const uint8_t req_[8] = {__VA_ARGS__};                                            \
        (void)fx_sdo(req_);                                                               \
    } while (0)
#define EXPECT(...) ASSERT_FRAME(fx.port.n_sent - 1U, 0x585U, 8, __VA_ARGS__)

static void upload_of_a_long_string(void)
{
    SDO(0x40, 0x09, 0x10, 0x00, 0, 0, 0, 0);
    EXPECT(0x41, 0x09, 0x10, 0x00, 24, 0, 0, 0);
    SDO(0x60, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(0x00, 'H', 'a', 'r', 'd', 'w', 'a', 'r');
    SDO(0x70, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(0x10, 'e', ' ', 'r', 'e', 'v', '.', ' ');
    SDO(0x60, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(0x00, '2', '.', '3', ' ', '(', 't', 'e');
    SDO(0x70, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(0x19, 's', 't', ')', 0, 0, 0, 0); /* last: 3 bytes, c = 1 */
    SDO(0x60, 0, 0, 0, 0, 0, 0, 0);           /* transfer over: a stray segment */
    EXPECT(0x80, 0x00, 0x00, 0x00, 0x01, 0x00, 0x04, 0x05);
}

static void short_objects_stay_expedited(void)
{
    SDO(0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    EXPECT(0x43, 0x08, 0x10, 0x00, 'E', 'S', '6', '1');
    SDO(0x2B, 0x17, 0x10, 0x00, 0x64, 0x00, 0, 0);
    EXPECT(0x60, 0x17, 0x10, 0x00, 0, 0, 0, 0);
}

static void upload_of_an_eight_byte_integer(void)
{
    SDO(0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0);
    EXPECT(0x41, 0x06, 0x20, 0x00, 8, 0, 0, 0);
    SDO(0x60, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(0x00, 0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02);
    SDO(0x70, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(0x1D, 0x01, 0, 0, 0, 0, 0, 0);
}

static void download_of_a_string(void)
{
    SDO(0x21, 0x05, 0x20, 0x00, 16, 0, 0, 0);
    EXPECT(0x60, 0x05, 0x20, 0x00, 0, 0, 0, 0);
    SDO(0x00, 's', 'e', 'g', 'm', 'e', 'n', 't');
    EXPECT(0x20, 0, 0, 0, 0, 0, 0, 0);
    SDO(0x10, 'e', 'd', ' ', 't', 'e', 'x', 't');
    EXPECT(0x30, 0, 0, 0, 0, 0, 0, 0);
    SDO(0x0B, '!', '!', 0, 0, 0, 0, 0); /* 2 bytes, last */
    EXPECT(0x20, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("segmented text!!", fx.values.x2005_description);
    SDO(0x20, 0x05, 0x20, 0x00, 0, 0, 0, 0); /* size not indicated */
    EXPECT(0x60, 0x05, 0x20, 0x00, 0, 0, 0, 0);
    SDO(0x09, 'a', 'b', 'c', 0, 0, 0, 0); /* 3 bytes, last */
    EXPECT(0x20, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("abc", fx.values.x2005_description);
}

static void toggle_error(void)
{
    SDO(0x21, 0x05, 0x20, 0x00, 16, 0, 0, 0);
    SDO(0x10, 'x', 'x', 'x', 'x', 'x', 'x', 'x');
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x00, 0x00, 0x03, 0x05);
    SDO(0x40, 0x09, 0x10, 0x00, 0, 0, 0, 0);
    SDO(0x70, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(0x80, 0x09, 0x10, 0x00, 0x00, 0x00, 0x03, 0x05);
    TEST_ASSERT_EQUAL_STRING("test node", fx.values.x2005_description);
}

static void timeout_aborts_at_exactly_one_second(void)
{
    SDO(0x21, 0x05, 0x20, 0x00, 16, 0, 0, 0);
    fx_advance(500000U);
    SDO(0x00, 's', 'e', 'g', 'm', 'e', 'n', 't'); /* restarts the timeout */
    fx_advance(CO_SDO_TIMEOUT_US - 1U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    fx_advance(1U);
    TEST_ASSERT_EQUAL_UINT32(3U, fx.port.n_sent);
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05);
    SDO(0x10, 'e', 'd', ' ', 't', 'e', 'x', 't'); /* too late */
    EXPECT(0x80, 0x00, 0x00, 0x00, 0x01, 0x00, 0x04, 0x05);
}

static void size_checks(void)
{
    SDO(0x21, 0x05, 0x20, 0x00, 21, 0, 0, 0); /* larger than the 20-byte object */
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x12, 0x00, 0x07, 0x06);
    SDO(0x21, 0x05, 0x20, 0x00, 10, 0, 0, 0);
    SDO(0x01, 'a', 'b', 'c', 'd', 'e', 'f', 'g'); /* 7 of 10, last */
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x13, 0x00, 0x07, 0x06);
    SDO(0x21, 0x05, 0x20, 0x00, 20, 0, 0, 0);
    SDO(0x00, '1', '2', '3', '4', '5', '6', '7');
    SDO(0x10, '1', '2', '3', '4', '5', '6', '7');
    SDO(0x01, '1', '2', '3', '4', '5', '6', '7'); /* 21 bytes */
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x12, 0x00, 0x07, 0x06);
    TEST_ASSERT_EQUAL_STRING("test node", fx.values.x2005_description);
}

static void access_checked_at_initiate(void)
{
    SDO(0x21, 0x09, 0x10, 0x00, 4, 0, 0, 0);
    EXPECT(0x80, 0x09, 0x10, 0x00, 0x02, 0x00, 0x01, 0x06);
    SDO(0x21, 0x00, 0x21, 0x00, 4, 0, 0, 0);
    EXPECT(0x80, 0x00, 0x21, 0x00, 0x00, 0x00, 0x02, 0x06);
    SDO(0x21, 0x05, 0x20, 0x07, 4, 0, 0, 0);
    EXPECT(0x80, 0x05, 0x20, 0x07, 0x11, 0x00, 0x09, 0x06);
    SDO(0x40, 0x00, 0x62, 0x01, 0, 0, 0, 0);
    EXPECT(0x80, 0x00, 0x62, 0x01, 0x01, 0x00, 0x01, 0x06);
}

static void device_refusal_at_the_end(void)
{
    fx.refuse_code = CO_ABORT_INVALID_VALUE;
    SDO(0x21, 0x05, 0x20, 0x00, 3, 0, 0, 0);
    SDO(0x09, 'a', 'b', 'c', 0, 0, 0, 0);
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x30, 0x00, 0x09, 0x06);
    TEST_ASSERT_EQUAL_STRING("test node", fx.values.x2005_description);
}

static void client_abort_and_new_initiate_end_a_transfer(void)
{
    SDO(0x21, 0x05, 0x20, 0x00, 16, 0, 0, 0);
    RX(0x605, 0x80, 0x05, 0x20, 0x00, 0, 0, 0x04, 0x05);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    SDO(0x00, 'x', 'x', 'x', 'x', 'x', 'x', 'x');
    EXPECT(0x80, 0x00, 0x00, 0x00, 0x01, 0x00, 0x04, 0x05);
    SDO(0x21, 0x05, 0x20, 0x00, 16, 0, 0, 0);
    SDO(0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0); /* a new request replaces the open transfer */
    EXPECT(0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x0F, 0x00);
    fx_advance(2000000U);
    TEST_ASSERT_EQUAL_HEX8(0x43, fx.port.sent[fx.port.n_sent - 1U].data[0]); /* no timeout abort */
}

static void stopped_node_drops_an_open_transfer_silently(void)
{
    SDO(0x21, 0x05, 0x20, 0x00, 16, 0, 0, 0);
    RX(0x000, 0x02, 0x05);
    const uint32_t sent = fx.port.n_sent;
    fx_advance(2U * CO_SDO_TIMEOUT_US);
    TEST_ASSERT_EQUAL_UINT32(sent, fx.port.n_sent); /* no timeout abort while Stopped */
    RX(0x000, 0x80, 0x05);
    SDO(0x00, 's', 'e', 'g', 'm', 'e', 'n', 't'); /* the transfer is gone */
    EXPECT(0x80, 0x00, 0x00, 0x00, 0x01, 0x00, 0x04, 0x05);
    TEST_ASSERT_EQUAL_STRING("test node", fx.values.x2005_description);
}

/* The server keeps the object of the transfer; a request that ends it is answered with its own multiplexer. */
static void a_request_during_a_transfer_has_its_own_multiplexer(void)
{
    SDO(0x21, 0x05, 0x20, 0x00, 16, 0, 0, 0);
    SDO(0xE0, 0x18, 0x10, 0x01, 0, 0, 0, 0); /* unknown command */
    EXPECT(0x80, 0x18, 0x10, 0x01, 0x01, 0x00, 0x04, 0x05);
    SDO(0x00, 's', 'e', 'g', 'm', 'e', 'n', 't'); /* the transfer is over */
    EXPECT(0x80, 0x00, 0x00, 0x00, 0x01, 0x00, 0x04, 0x05);
    SDO(0x40, 0x09, 0x10, 0x00, 0, 0, 0, 0);
    SDO(0x60, 0, 0, 0, 0, 0, 0, 0);
    SDO(0x21, 0x05, 0x20, 0x00, 16, 0, 0, 0); /* a download initiate in the middle of an upload */
    EXPECT(0x60, 0x05, 0x20, 0x00, 0, 0, 0, 0);
    fx_advance(CO_SDO_TIMEOUT_US);
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05); /* the timeout names the new transfer's object */
}

/* A frame that is no SDO request (DLC other than 8) is ignored: it does not restart the timeout either. */
static void a_short_frame_does_not_restart_the_timeout(void)
{
    SDO(0x21, 0x05, 0x20, 0x00, 16, 0, 0, 0);
    fx_advance(CO_SDO_TIMEOUT_US / 2U);
    RX(0x605, 0x00, 's', 'e', 'g', 'm', 'e', 'n'); /* 7 bytes */
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    fx_advance(CO_SDO_TIMEOUT_US / 2U);
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(upload_of_a_long_string);
    RUN_TEST(short_objects_stay_expedited);
    RUN_TEST(upload_of_an_eight_byte_integer);
    RUN_TEST(download_of_a_string);
    RUN_TEST(toggle_error);
    RUN_TEST(timeout_aborts_at_exactly_one_second);
    RUN_TEST(size_checks);
    RUN_TEST(access_checked_at_initiate);
    RUN_TEST(device_refusal_at_the_end);
    RUN_TEST(client_abort_and_new_initiate_end_a_transfer);
    RUN_TEST(stopped_node_drops_an_open_transfer_silently);
    RUN_TEST(a_request_during_a_transfer_has_its_own_multiplexer);
    RUN_TEST(a_short_frame_does_not_restart_the_timeout);
    return UNITY_END();
}
