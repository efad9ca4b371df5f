/* The motor board's hardware in one place: MCU clock, every pin, the PWM, the encoders' counts per wheel
 * revolution and the firmware's timing. An Arduino Uno/Nano-class ATmega328P at 16 MHz drives the three
 * 12 V motors of the Nexus 15001 3WD base through a PWM + DIR H-bridge per motor with one shared
 * enable (standby) line, e.g. a TB6612FNG pair or three MC33886 / L298-style channels.
 *
 * Wiring (Arduino pin names in brackets):
 *   host serial      PD0 RXD [D0], PD1 TXD [D1] (the USB serial adapter), 115200 8N1
 *   motor 0 (wheel_0) PWM  PD6 OC0A [D6]   DIR PD4 [D4]
 *   motor 1 (wheel_1) PWM  PD5 OC0B [D5]   DIR PD7 [D7]
 *   motor 2 (wheel_2) PWM  PD3 OC2B [D3]   DIR PB0 [D8]
 *   driver enable    PD2 [D2]: high = the bridges drive; low = standby (outputs open, the motors coast)
 *   encoder 0 A/B    PC0 [A0] / PC1 [A1]
 *   encoder 1 A/B    PC2 [A2] / PC3 [A3]
 *   encoder 2 A/B    PC4 [A4] / PC5 [A5]   (all six on pin-change interrupt PCINT1)
 *   busy             PB5 [D13, the LED]: high while the main loop works, low while it sleeps (a scope
 *                    on it shows the loop's time per cycle; the simulator harness measures it there)
 * Put 10 k pull-downs on the three PWM pins and the enable pin: from reset until the firmware sets them
 * (and on a watchdog reset) the pins float, and the pull-downs keep the bridges in standby.
 * A wheel turning forward (positive duty, the robot moving along its drive direction) must count up:
 * encoder A leads B. If a wheel counts down when driven forward, swap its A and B wires; if it turns
 * backwards, swap its motor leads. */
#ifndef MOTOR_BOARD_CONFIG_H
#define MOTOR_BOARD_CONFIG_H

#ifdef __AVR__
#include <avr/io.h>
#endif

#include "omni_base/motor_wire.h"

#ifndef F_CPU
#define F_CPU 16000000UL
#endif

#define BOARD_WHEELS 3u
#define BOARD_BAUD MP_DEFAULT_BAUD

/* Encoder counts per wheel revolution: 11 lines per motor revolution x 30:1 gearbox x 4 edges
 * (quadrature, both edges of both channels). config/omni_base.yaml wheels/encoder_counts_per_rev must
 * say the same (a gtest checks it); the firmware itself only counts edges. */
#define ENCODER_LINES_PER_MOTOR_REV 11u
#define GEAR_RATIO 30u
#define ENCODER_COUNTS_PER_WHEEL_REV (ENCODER_LINES_PER_MOTOR_REV * GEAR_RATIO * 4u)

/* PWM: timers 0 and 2 in 8-bit fast PWM, prescaler 8: 16 MHz / 8 / 256 = 7.8 kHz (within what
 * MC33886, L298 and TB6612 bridges take). A duty of n/256 of the supply sets OCR = n - 1; zero duty
 * disconnects the pin from the timer and drives it low (fast PWM would still pulse 1/256 at OCR = 0). */
#define PWM_STEPS 256u

/* Pins as port letter and bit, so that the simulator harness (C++) reads this same header. */
#define MOTOR0_PWM_PORT D /* OC0A */
#define MOTOR0_PWM_BIT 6
#define MOTOR1_PWM_PORT D /* OC0B */
#define MOTOR1_PWM_BIT 5
#define MOTOR2_PWM_PORT D /* OC2B */
#define MOTOR2_PWM_BIT 3
#define MOTOR0_DIR_PORT D
#define MOTOR0_DIR_BIT 4
#define MOTOR1_DIR_PORT D
#define MOTOR1_DIR_BIT 7
#define MOTOR2_DIR_PORT B
#define MOTOR2_DIR_BIT 0
#define DRIVER_ENABLE_PORT D
#define DRIVER_ENABLE_BIT 2
#define ENCODER_PORT_LETTER C /* encoder i: A on bit 2i, B on bit 2i + 1 (PCINT1) */
#define ENCODER_MASK 0x3Fu
#define BUSY_PORT_LETTER B
#define BUSY_BIT 5

#ifdef __AVR__
#define BOARD_CAT_(a, b) a##b
#define BOARD_CAT(a, b) BOARD_CAT_(a, b)
#define PORT_OF(letter) BOARD_CAT(PORT, letter)
#define DDR_OF(letter) BOARD_CAT(DDR, letter)
#define PIN_OF(letter) BOARD_CAT(PIN, letter)
#define ENCODER_PCMSK PCMSK1
#define ENCODER_PCIE PCIE1
#endif

/* Timing. The board clock ticks at 1 kHz (timer 1, CTC): board time in ms and the command watchdog
 * (MP_BOARD_WATCHDOG_MS without a valid command stops the motors). The hardware watchdog resets the
 * MCU if the main loop stops for 120 ms (a reset leaves the pins floating: the bridges in standby). */
#define TICK_HZ 1000u
#define HARDWARE_WATCHDOG WDTO_120MS

/* Serial buffers (powers of two). 64 received bytes are 5.6 ms of line at 115200 baud; a STATE reply
 * is 28 bytes, so two fit the transmit ring. A reply that does not fit is dropped (the host asks again
 * within one control cycle), so a flood of commands never blocks the loop. */
#define SERIAL_RX_RING 64u
#define SERIAL_TX_RING 64u

#endif
