/* The 1 kHz board clock: board time (ms since power-up, wrapping u32) and the command watchdog, which
 * stops the motors from the tick interrupt itself, whatever the main loop is doing. */
#ifndef MOTOR_BOARD_CLOCK_H
#define MOTOR_BOARD_CLOCK_H

#include <stdint.h>

void board_clock_init(void);
/* Board time; the caller keeps interrupts off (it is latched with the encoder counts). */
uint32_t board_time_ms_locked(void);
/* A valid command arrived: restarts the watchdog and clears its stop. Interrupts off. */
void board_clock_command_received_locked(void);
/* Whether the watchdog stopped the motors since the last valid command. */
uint8_t board_clock_watchdog_stopped(void);

#endif
