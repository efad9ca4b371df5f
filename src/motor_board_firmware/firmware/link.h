/* The board side of the motor protocol (omni_base/motor_wire.h): decodes the host's frames, applies
 * ENABLE and SET_DUTY, answers each valid one with a STATE frame. */
#ifndef MOTOR_BOARD_LINK_H
#define MOTOR_BOARD_LINK_H

#include "omni_base/motor_wire.h"

void link_init(void);
/* Decodes at most LINK_BYTES_PER_POLL received bytes and acts on the frames they complete: bounded
 * work per call, so a flood cannot keep the main loop from the hardware watchdog. */
void link_poll(void);

#define LINK_BYTES_PER_POLL 16u

/* The decoder (its counters are read by the harness). */
extern mp_decoder link_decoder;

#endif
