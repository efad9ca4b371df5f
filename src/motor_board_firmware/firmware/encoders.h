/* Quadrature encoder counting on pin-change interrupts: every edge of A and B, free-running 32-bit
 * counters (they wrap; the host handles that with wheels/encoder_bits 32). */
#ifndef MOTOR_BOARD_ENCODERS_H
#define MOTOR_BOARD_ENCODERS_H

#include <stdint.h>

#include "board_config.h"

void encoders_init(void);
/* Copies the counters; the caller keeps interrupts off so they are latched with the board time. */
void encoders_copy(int32_t counts[BOARD_WHEELS]);

/* Transitions where both channels changed at once (an edge missed): the count cannot tell the direction
 * and is left as it is. Read by the simulator harness; never expected. */
extern volatile uint16_t encoder_glitches;

#endif
