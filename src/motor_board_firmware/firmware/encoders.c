#include "encoders.h"

#include <avr/interrupt.h>
#include <avr/io.h>

static volatile int32_t counts[BOARD_WHEELS];
static volatile uint8_t previous_pins;
volatile uint16_t encoder_glitches;

/* Count step for (previous state << 2 | new state), state = A | B << 1. Forward (A leads B) runs
 * 0 -> 1 -> 3 -> 2 -> 0. Entries of 2 mark a transition with both channels changed. */
static const int8_t kStep[16] = {
    0, +1, -1, 2,   /* from 0 */
    -1, 0, 2, +1,   /* from 1 */
    +1, 2, 0, -1,   /* from 2 */
    2, -1, +1, 0,   /* from 3 */
};

void encoders_init(void) {
  DDR_OF(ENCODER_PORT_LETTER) &= (uint8_t)~ENCODER_MASK;
  PORT_OF(ENCODER_PORT_LETTER) |= ENCODER_MASK; /* pull-ups: an unplugged encoder reads a steady 1, not noise */
  previous_pins = PIN_OF(ENCODER_PORT_LETTER) & ENCODER_MASK;
  ENCODER_PCMSK = ENCODER_MASK;
  PCICR |= _BV(ENCODER_PCIE);
}

ISR(PCINT1_vect) {
  const uint8_t now = PIN_OF(ENCODER_PORT_LETTER) & ENCODER_MASK;
  uint8_t old = previous_pins;
  uint8_t pins = now;
  uint8_t wheel;
  previous_pins = now;
  for (wheel = 0; wheel < BOARD_WHEELS; ++wheel) {
    const int8_t step = kStep[((old & 3u) << 2) | (pins & 3u)];
    if (step == 2) {
      ++encoder_glitches;
    } else if (step != 0) {
      counts[wheel] += step;
    }
    old >>= 2;
    pins >>= 2;
  }
}

void encoders_copy(int32_t out[BOARD_WHEELS]) {
  uint8_t wheel;
  for (wheel = 0; wheel < BOARD_WHEELS; ++wheel) out[wheel] = counts[wheel];
}
