#include "link.h"

#include <util/atomic.h>

#include "board_clock.h"
#include "board_config.h"
#include "encoders.h"
#include "motors.h"
#include "serial.h"

mp_decoder link_decoder;

void link_init(void) { mp_decoder_init(&link_decoder); }

/* The STATE frame answering command `sequence`: counters and board time latched together. */
static void reply_state(uint8_t sequence) {
  uint8_t payload[MP_STATE_SIZE(BOARD_WHEELS)];
  uint8_t frame[MP_STATE_SIZE(BOARD_WHEELS) + MP_HEADER_SIZE + MP_CRC_SIZE];
  int32_t counts[BOARD_WHEELS];
  uint32_t now_ms;
  uint8_t wheel;
  ATOMIC_BLOCK(ATOMIC_FORCEON) {
    encoders_copy(counts);
    now_ms = board_time_ms_locked();
  }
  payload[MP_STATE_SEQUENCE] = sequence;
  payload[MP_STATE_STATUS] = (uint8_t)((motors_enabled() ? MP_STATUS_ENABLED : 0u) |
                                       (board_clock_watchdog_stopped() ? MP_STATUS_WATCHDOG_STOPPED : 0u));
  payload[MP_STATE_FAULTS] = 0; /* no current or voltage sensing on this board */
  payload[MP_STATE_COUNT] = BOARD_WHEELS;
  for (wheel = 0; wheel < BOARD_WHEELS; ++wheel) {
    mp_put_u32le(&payload[MP_STATE_COUNTS + 4u * wheel], (uint32_t)counts[wheel]);
  }
  mp_put_u32le(&payload[MP_STATE_TIME(BOARD_WHEELS)], now_ms);
  serial_write(frame, (uint8_t)mp_encode_frame(frame, MP_TYPE_STATE, payload, sizeof payload));
}

/* A SET_DUTY for this board's wheel count with every duty in range; anything else is ignored. */
static uint8_t duty_frame_valid(const mp_frame* frame) {
  uint8_t wheel;
  if (frame->length != MP_SET_DUTY_SIZE(BOARD_WHEELS) || frame->payload[MP_SET_DUTY_COUNT] != BOARD_WHEELS) return 0;
  for (wheel = 0; wheel < BOARD_WHEELS; ++wheel) {
    const int16_t duty = (int16_t)mp_get_u16le(&frame->payload[MP_SET_DUTY_DUTIES + 2u * wheel]);
    if (duty > MP_DUTY_FULL_SCALE || duty < -MP_DUTY_FULL_SCALE) return 0;
  }
  return 1;
}

static void apply_duty(const mp_frame* frame) {
  uint8_t wheel;
  ATOMIC_BLOCK(ATOMIC_FORCEON) {
    board_clock_command_received_locked();
    for (wheel = 0; wheel < BOARD_WHEELS; ++wheel) {
      motors_set_duty(wheel, (int16_t)mp_get_u16le(&frame->payload[MP_SET_DUTY_DUTIES + 2u * wheel]));
    }
  }
}

static void apply_enable(uint8_t enable) {
  ATOMIC_BLOCK(ATOMIC_FORCEON) {
    board_clock_command_received_locked();
    if (enable != motors_enabled()) motors_set_enabled(enable); /* a repeated ENABLE keeps the duties */
  }
}

static void handle_frame(const mp_frame* frame) {
  if (frame->type == MP_TYPE_SET_DUTY && duty_frame_valid(frame)) {
    apply_duty(frame);
    reply_state(frame->payload[MP_SET_DUTY_SEQUENCE]);
  } else if (frame->type == MP_TYPE_ENABLE && frame->length == MP_ENABLE_SIZE && frame->payload[MP_ENABLE_FLAG] <= 1) {
    apply_enable(frame->payload[MP_ENABLE_FLAG]);
    reply_state(frame->payload[MP_ENABLE_SEQUENCE]);
  }
  /* Unknown types, STATE frames (an echo), wrong wheel counts: no reply, nothing changes. */
}

void link_poll(void) {
  uint8_t bytes[LINK_BYTES_PER_POLL];
  const uint8_t n = serial_read(bytes, sizeof bytes);
  uint8_t taken = 0;
  mp_frame frame;
  while (taken < n) {
    taken = (uint8_t)(taken + mp_decoder_put(&link_decoder, bytes + taken, (size_t)(n - taken)));
    while (mp_decoder_next(&link_decoder, &frame)) handle_frame(&frame);
  }
}
