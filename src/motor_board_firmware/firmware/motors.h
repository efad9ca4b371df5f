/* The three motor channels: PWM + direction per motor and the bridges' shared enable line. */
#ifndef MOTOR_BOARD_MOTORS_H
#define MOTOR_BOARD_MOTORS_H

#include <stdint.h>

/* The safe state, first thing after reset: every motor pin an output driven low (bridges in standby,
 * zero duty), PWM timers running with their pins disconnected. */
void motors_init(void);
/* Drives (1) or puts the bridges in standby (0); either way every duty starts from zero. */
void motors_set_enabled(uint8_t enabled);
uint8_t motors_enabled(void);
/* Duty of motor `motor` in 1/MP_DUTY_FULL_SCALE of the supply, sign = direction. Ignored while disabled.
 * Callers keep interrupts off around a set of duties (the board clock's watchdog zeroes them). */
void motors_set_duty(uint8_t motor, int16_t duty);
/* Every duty to zero; the enable line stays as it is (a bridge at zero duty brakes). */
void motors_zero(void);

#endif
