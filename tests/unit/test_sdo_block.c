/* SDO block transfer (CiA 301 §7.2.4.3.9-16): the frame sequences of block upload and download, the CRC, the
 * protocol switch, lost and repeated segments, the block abort codes and the timeout. CRC values are CRC-16/XMODEM
 * (polynomial 0x1021, start 0), the CiA 301 CRC: "123456789" -> 0x31C3. */
#include <string.h>

#include "fixture.h"

void setUp(void)
{
    fx_start(5U, CO_OPT_SDO_SEGMENTED | CO_OPT_SDO_BLOCK);
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

#define SDO(...)                                                                          \
    do {                                                                                  \
        const uint8_t req_[8] = {__VA_ARGS__};                                            \
        fx_rx(0x605U, 8U, req_);                                                          \
        (void)fx_process();                                                               \
    } while (0)
#define FRAME(i, ...) ASSERT_FRAME((i), 0x585U, 8, __VA_ARGS__)
#define EXPECT(...) FRAME(fx.port.n_sent - 1U, __VA_ARGS__)
#define SENT(n) TEST_ASSERT_EQUAL_UINT32((n), fx.port.n_sent)

/* 0x1009 is "Hardware rev. 2.3 (test)": 24 bytes, four segments, CRC 0x3F0F. */
static void upload_with_crc(void)
{
    SDO(0xA4, 0x09, 0x10, 0x00, 127, 0, 0, 0); /* client CRC, blksize 127, no protocol switch */
    EXPECT(0xC6, 0x09, 0x10, 0x00, 24, 0, 0, 0);
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0);
    SENT(5U);
    FRAME(1U, 0x01, 'H', 'a', 'r', 'd', 'w', 'a', 'r');
    FRAME(2U, 0x02, 'e', ' ', 'r', 'e', 'v', '.', ' ');
    FRAME(3U, 0x03, '2', '.', '3', ' ', '(', 't', 'e');
    FRAME(4U, 0x84, 's', 't', ')', 0, 0, 0, 0); /* c bit: the last segment */
    SDO(0xA2, 4, 127, 0, 0, 0, 0, 0);
    EXPECT(0xD1, 0x0F, 0x3F, 0, 0, 0, 0, 0); /* end: 4 unused bytes, CRC */
    SDO(0xA1, 0, 0, 0, 0, 0, 0, 0);          /* end response: no answer, transfer over */
    SENT(6U);
    SDO(0xA1, 0, 0, 0, 0, 0, 0, 0); /* a stray end response */
    EXPECT(0x80, 0, 0, 0, 0x01, 0x00, 0x04, 0x05);
}

static void upload_without_crc_of_a_short_object(void)
{
    SDO(0xA0, 0x00, 0x10, 0x00, 16, 0, 0, 0); /* no client CRC: the CRC field is 0 */
    EXPECT(0xC6, 0x00, 0x10, 0x00, 4, 0, 0, 0);
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(0x81, 0x91, 0x01, 0x0F, 0x00, 0, 0, 0);
    SDO(0xA2, 1, 16, 0, 0, 0, 0, 0);
    EXPECT(0xCD, 0, 0, 0, 0, 0, 0, 0);
    SDO(0xA4, 0x00, 0x10, 0x00, 16, 0, 0, 0);
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0);
    SDO(0xA2, 1, 16, 0, 0, 0, 0, 0);
    EXPECT(0xCD, 0x25, 0x97, 0, 0, 0, 0, 0); /* with CRC */
}

static void protocol_switch_at_the_threshold(void)
{
    SDO(0xA4, 0x09, 0x10, 0x00, 127, 24, 0, 0); /* 24 bytes <= pst 24: an ordinary segmented upload */
    EXPECT(0x41, 0x09, 0x10, 0x00, 24, 0, 0, 0);
    SDO(0x60, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(0x00, 'H', 'a', 'r', 'd', 'w', 'a', 'r');
    SDO(0xA4, 0x00, 0x10, 0x00, 127, 4, 0, 0); /* 4 bytes: expedited */
    EXPECT(0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x0F, 0x00);
    SDO(0xA4, 0x09, 0x10, 0x00, 127, 23, 0, 0); /* 24 > 23: block */
    EXPECT(0xC6, 0x09, 0x10, 0x00, 24, 0, 0, 0);
}

static void upload_repeats_from_the_last_confirmed_segment(void)
{
    SDO(0xA4, 0x09, 0x10, 0x00, 2, 0, 0, 0); /* two segments per block */
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0);
    SENT(3U);
    FRAME(2U, 0x02, 'e', ' ', 'r', 'e', 'v', '.', ' ');
    SDO(0xA2, 1, 3, 0, 0, 0, 0, 0); /* segment 2 lost; next block of 3 */
    SENT(6U);
    FRAME(3U, 0x01, 'e', ' ', 'r', 'e', 'v', '.', ' ');
    FRAME(4U, 0x02, '2', '.', '3', ' ', '(', 't', 'e');
    FRAME(5U, 0x83, 's', 't', ')', 0, 0, 0, 0);
    SDO(0xA2, 0, 3, 0, 0, 0, 0, 0); /* the whole block lost */
    SENT(9U);
    FRAME(6U, 0x01, 'e', ' ', 'r', 'e', 'v', '.', ' ');
    FRAME(8U, 0x83, 's', 't', ')', 0, 0, 0, 0);
    SDO(0xA2, 3, 3, 0, 0, 0, 0, 0);
    EXPECT(0xD1, 0x0F, 0x3F, 0, 0, 0, 0, 0);
}

static void upload_block_size_and_sequence_errors(void)
{
    SDO(0xA4, 0x09, 0x10, 0x00, 0, 0, 0, 0);
    EXPECT(0x80, 0x09, 0x10, 0x00, 0x02, 0x00, 0x04, 0x05);
    SDO(0xA4, 0x09, 0x10, 0x00, 128, 0, 0, 0);
    EXPECT(0x80, 0x09, 0x10, 0x00, 0x02, 0x00, 0x04, 0x05);
    SDO(0xA4, 0x09, 0x10, 0x00, 2, 0, 0, 0);
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0);
    SDO(0xA2, 2, 0, 0, 0, 0, 0, 0); /* next block size 0 */
    EXPECT(0x80, 0x09, 0x10, 0x00, 0x02, 0x00, 0x04, 0x05);
    SDO(0xA4, 0x09, 0x10, 0x00, 2, 0, 0, 0);
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0);
    SDO(0xA2, 3, 2, 0, 0, 0, 0, 0); /* confirms a segment never sent */
    EXPECT(0x80, 0x09, 0x10, 0x00, 0x03, 0x00, 0x04, 0x05);
    SDO(0xA4, 0x00, 0x62, 0x01, 2, 0, 0, 0); /* write-only: the object's own abort */
    EXPECT(0x80, 0x00, 0x62, 0x01, 0x01, 0x00, 0x01, 0x06);
    SDO(0xA4, 0x00, 0x21, 0x00, 2, 0, 0, 0);
    EXPECT(0x80, 0x00, 0x21, 0x00, 0x00, 0x00, 0x02, 0x06);
}

/* A port that is busy holds the block back: the node sends the rest from co_node_process, never more than its
 * transmit queue holds, in order. */
static void upload_block_waits_for_a_busy_port(void)
{
    SDO(0xA4, 0x09, 0x10, 0x00, 127, 0, 0, 0);
    fx.port.busy_count = 3U;
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.node.txq.count); /* segment 1 queued, nothing else pushed behind it */
    fx_advance(10000U);
    SENT(5U);
    FRAME(1U, 0x01, 'H', 'a', 'r', 'd', 'w', 'a', 'r');
    FRAME(4U, 0x84, 's', 't', ')', 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.node.stats.tx_dropped);
}

/* An empty object is one segment with 7 unused bytes. A confirmation that comes before the port took any segment of
 * the block (ackseq 0 of none sent) confirms nothing: the block still goes out, and the end follows its own
 * confirmation. */
static void upload_of_an_empty_object_confirmed_before_its_block(void)
{
    SDO(0x21, 0x05, 0x20, 0x00, 0, 0, 0, 0); /* segmented download of 0 bytes */
    SDO(0x0F, 0, 0, 0, 0, 0, 0, 0);          /* its only segment: 7 bytes unused, the last */
    EXPECT(0x20, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("", fx.values.x2005_description);
    const uint32_t before = fx.port.n_sent;
    fx.port.busy_count = 100U;                 /* a busy port: */
    SDO(0xA4, 0x05, 0x20, 0x00, 127, 0, 0, 0); /* the answer waits in the queue */
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0);            /* no segment goes behind it */
    SDO(0xA2, 0, 127, 0, 0, 0, 0, 0);          /* confirms none */
    SENT(before);
    fx.port.busy_count = 0U;
    fx_advance(10000U);
    SENT(before + 2U);
    FRAME(before, 0xC6, 0x05, 0x20, 0x00, 0, 0, 0, 0);
    FRAME(before + 1U, 0x81, 0, 0, 0, 0, 0, 0, 0);
    SDO(0xA2, 1, 127, 0, 0, 0, 0, 0);
    EXPECT(0xDD, 0, 0, 0, 0, 0, 0, 0); /* end: 7 unused bytes, the CRC of nothing */
}

static void download_with_crc(void)
{
    SDO(0xC6, 0x05, 0x20, 0x00, 9, 0, 0, 0); /* client CRC, size 9 */
    EXPECT(0xA4, 0x05, 0x20, 0x00, 10, 0, 0, 0); /* blksize: the 64-byte buffer in segments */
    SDO(0x01, '1', '2', '3', '4', '5', '6', '7');
    SENT(1U);
    SDO(0x82, '8', '9', 0, 0, 0, 0, 0);
    EXPECT(0xA2, 2, 10, 0, 0, 0, 0, 0);
    SDO(0xD5, 0xC3, 0x31, 0, 0, 0, 0, 0); /* 5 unused bytes, CRC 0x31C3 */
    EXPECT(0xA1, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("123456789", fx.values.x2005_description);
}

static void download_with_a_bad_crc_is_refused(void)
{
    SDO(0xC4, 0x05, 0x20, 0x00, 0, 0, 0, 0); /* size not indicated */
    SDO(0x01, '1', '2', '3', '4', '5', '6', '7');
    SDO(0x82, '8', '9', 0, 0, 0, 0, 0);
    SDO(0xD5, 0xC4, 0x31, 0, 0, 0, 0, 0);
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x04, 0x00, 0x04, 0x05);
    TEST_ASSERT_EQUAL_STRING("test node", fx.values.x2005_description);
    SDO(0xC0, 0x05, 0x20, 0x00, 0, 0, 0, 0); /* without client CRC the field is not looked at */
    SDO(0x81, 'a', 'b', 'c', 0, 0, 0, 0);
    SDO(0xD1, 0x12, 0x34, 0, 0, 0, 0, 0);
    EXPECT(0xA1, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("abc", fx.values.x2005_description);
}

static void download_lost_and_repeated_segments(void)
{
    SDO(0xC6, 0x05, 0x20, 0x00, 17, 0, 0, 0);
    SDO(0x01, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    SDO(0x01, 'a', 'b', 'c', 'd', 'e', 'f', 'g'); /* repeated: ignored */
    SDO(0x03, 'X', 'X', 'X', 'X', 'X', 'X', 'X'); /* 2 lost: ignored */
    SDO(0x84, 'Y', 'Y', 'Y', 0, 0, 0, 0);         /* last of the block: confirms 1 */
    EXPECT(0xA2, 1, 9, 0, 0, 0, 0, 0);            /* 57 bytes of room left: 9 segments */
    SDO(0x01, 'h', 'i', 'j', 'k', 'l', 'm', 'n');
    SDO(0x82, 'o', 'p', 'q', 0, 0, 0, 0);
    EXPECT(0xA2, 2, 9, 0, 0, 0, 0, 0); /* after the last segment the block size is not renegotiated */
    SDO(0xD1, 0xD2, 0x10, 0, 0, 0, 0, 0); /* 4 unused bytes, CRC of "abcdefghijklmnopq" */
    EXPECT(0xA1, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("abcdefghijklmnopq", fx.values.x2005_description);
}

static void download_sequence_size_and_memory_errors(void)
{
    SDO(0xC2, 0x05, 0x20, 0x00, 21, 0, 0, 0); /* larger than the 20-byte object */
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x12, 0x00, 0x07, 0x06);
    SDO(0xC2, 0x05, 0x20, 0x00, 65, 0, 0, 0);
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x12, 0x00, 0x07, 0x06);
    SDO(0xC2, 0x09, 0x10, 0x00, 4, 0, 0, 0); /* const */
    EXPECT(0x80, 0x09, 0x10, 0x00, 0x02, 0x00, 0x01, 0x06);
    SDO(0xC2, 0x05, 0x20, 0x07, 4, 0, 0, 0);
    EXPECT(0x80, 0x05, 0x20, 0x07, 0x11, 0x00, 0x09, 0x06);
    SDO(0xC0, 0x05, 0x20, 0x00, 0, 0, 0, 0);
    SDO(0x00, 'a', 'b', 'c', 'd', 'e', 'f', 'g'); /* sequence number 0 */
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x03, 0x00, 0x04, 0x05);
    SDO(0xC0, 0x05, 0x20, 0x00, 0, 0, 0, 0);
    SDO(0x0B, 'a', 'b', 'c', 'd', 'e', 'f', 'g'); /* 11 > blksize 10 */
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x03, 0x00, 0x04, 0x05);
    SDO(0xC2, 0x05, 0x20, 0x00, 10, 0, 0, 0);
    SDO(0x81, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    SDO(0xD1, 0, 0, 0, 0, 0, 0, 0); /* 3 bytes of 10 */
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x13, 0x00, 0x07, 0x06);
    SDO(0xC0, 0x05, 0x20, 0x00, 0, 0, 0, 0); /* more than the buffer, size not indicated */
    for (uint8_t seq = 1U; seq <= 10U; seq++) {
        SDO(seq, 'x', 'x', 'x', 'x', 'x', 'x', 'x');
    }
    EXPECT(0xA2, 10, 1, 0, 0, 0, 0, 0); /* no room left: blksize 1 */
    SDO(0x81, 'x', 'x', 'x', 'x', 'x', 'x', 'x');
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x05, 0x00, 0x04, 0x05);
    TEST_ASSERT_EQUAL_STRING("test node", fx.values.x2005_description);
}

static void timeout_aborts_at_exactly_one_second(void)
{
    SDO(0xC2, 0x05, 0x20, 0x00, 9, 0, 0, 0);
    fx_advance(500000U);
    SDO(0x01, '1', '2', '3', '4', '5', '6', '7'); /* restarts the timeout */
    fx_advance(CO_SDO_TIMEOUT_US - 1U);
    SENT(1U);
    fx_advance(1U);
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05);
    SDO(0xA4, 0x09, 0x10, 0x00, 127, 0, 0, 0);
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0);
    fx_advance(CO_SDO_TIMEOUT_US); /* no confirmation of the block */
    EXPECT(0x80, 0x09, 0x10, 0x00, 0x00, 0x00, 0x04, 0x05);
}

static void block_off_answers_command_unknown(void)
{
    fx_start(5U, CO_OPT_SDO_SEGMENTED);
    fake_port_clear(&fx.port);
    SDO(0xA4, 0x09, 0x10, 0x00, 127, 0, 0, 0);
    EXPECT(0x80, 0x09, 0x10, 0x00, 0x01, 0x00, 0x04, 0x05);
    SDO(0xC6, 0x05, 0x20, 0x00, 9, 0, 0, 0);
    EXPECT(0x80, 0x05, 0x20, 0x00, 0x01, 0x00, 0x04, 0x05);
    SDO(0xA3, 0, 0, 0, 0, 0, 0, 0); /* a sub-command without a transfer: no multiplexer to echo */
    EXPECT(0x80, 0, 0, 0, 0x01, 0x00, 0x04, 0x05);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(upload_with_crc);
    RUN_TEST(upload_without_crc_of_a_short_object);
    RUN_TEST(protocol_switch_at_the_threshold);
    RUN_TEST(upload_repeats_from_the_last_confirmed_segment);
    RUN_TEST(upload_block_size_and_sequence_errors);
    RUN_TEST(upload_block_waits_for_a_busy_port);
    RUN_TEST(upload_of_an_empty_object_confirmed_before_its_block);
    RUN_TEST(download_with_crc);
    RUN_TEST(download_with_a_bad_crc_is_refused);
    RUN_TEST(download_lost_and_repeated_segments);
    RUN_TEST(download_sequence_size_and_memory_errors);
    RUN_TEST(timeout_aborts_at_exactly_one_second);
    RUN_TEST(block_off_answers_command_unknown);
    return UNITY_END();
}
