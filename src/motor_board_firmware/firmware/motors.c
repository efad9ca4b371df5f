#include "motors.h"

#include <avr/io.h>

#include "board_config.h"

static uint8_t enabled;

void motors_init(void) {
  PORT_OF(DRIVER_ENABLE_PORT) &= (uint8_t)~_BV(DRIVER_ENABLE_BIT);
  DDR_OF(DRIVER_ENABLE_PORT) |= _BV(DRIVER_ENABLE_BIT);
  PORT_OF(MOTOR0_PWM_PORT) &= (uint8_t)~_BV(MOTOR0_PWM_BIT);
  PORT_OF(MOTOR1_PWM_PORT) &= (uint8_t)~_BV(MOTOR1_PWM_BIT);
  PORT_OF(MOTOR2_PWM_PORT) &= (uint8_t)~_BV(MOTOR2_PWM_BIT);
  PORT_OF(MOTOR0_DIR_PORT) &= (uint8_t)~_BV(MOTOR0_DIR_BIT);
  PORT_OF(MOTOR1_DIR_PORT) &= (uint8_t)~_BV(MOTOR1_DIR_BIT);
  PORT_OF(MOTOR2_DIR_PORT) &= (uint8_t)~_BV(MOTOR2_DIR_BIT);
  DDR_OF(MOTOR0_PWM_PORT) |= _BV(MOTOR0_PWM_BIT);
  DDR_OF(MOTOR1_PWM_PORT) |= _BV(MOTOR1_PWM_BIT);
  DDR_OF(MOTOR2_PWM_PORT) |= _BV(MOTOR2_PWM_BIT);
  DDR_OF(MOTOR0_DIR_PORT) |= _BV(MOTOR0_DIR_BIT);
  DDR_OF(MOTOR1_DIR_PORT) |= _BV(MOTOR1_DIR_BIT);
  DDR_OF(MOTOR2_DIR_PORT) |= _BV(MOTOR2_DIR_BIT);
  /* Fast PWM 8-bit (mode 3), clock / 8, output compare pins disconnected. */
  TCCR0A = _BV(WGM01) | _BV(WGM00);
  TCCR0B = _BV(CS01);
  TCCR2A = _BV(WGM21) | _BV(WGM20);
  TCCR2B = _BV(CS21);
  enabled = 0;
}

/* PWM steps (0..PWM_STEPS) for a duty magnitude in 1/MP_DUTY_FULL_SCALE, rounded. */
static uint16_t pwm_steps(uint16_t magnitude) {
  return (uint16_t)(((uint32_t)magnitude * PWM_STEPS + MP_DUTY_FULL_SCALE / 2) / MP_DUTY_FULL_SCALE);
}

/* Sets one output compare: steps == 0 disconnects the pin (held low by its PORT bit). */
static void set_pwm(uint8_t motor, uint16_t steps) {
  const uint8_t ocr = steps == 0 ? 0 : (uint8_t)(steps - 1);
  switch (motor) {
    case 0:
      OCR0A = ocr;
      TCCR0A = steps == 0 ? (uint8_t)(TCCR0A & ~_BV(COM0A1)) : (uint8_t)(TCCR0A | _BV(COM0A1));
      break;
    case 1:
      OCR0B = ocr;
      TCCR0A = steps == 0 ? (uint8_t)(TCCR0A & ~_BV(COM0B1)) : (uint8_t)(TCCR0A | _BV(COM0B1));
      break;
    default:
      OCR2B = ocr;
      TCCR2A = steps == 0 ? (uint8_t)(TCCR2A & ~_BV(COM2B1)) : (uint8_t)(TCCR2A | _BV(COM2B1));
      break;
  }
}

static void set_direction(uint8_t motor, uint8_t reverse) {
  switch (motor) {
    case 0:
      if (reverse) PORT_OF(MOTOR0_DIR_PORT) |= _BV(MOTOR0_DIR_BIT); else PORT_OF(MOTOR0_DIR_PORT) &= (uint8_t)~_BV(MOTOR0_DIR_BIT);
      break;
    case 1:
      if (reverse) PORT_OF(MOTOR1_DIR_PORT) |= _BV(MOTOR1_DIR_BIT); else PORT_OF(MOTOR1_DIR_PORT) &= (uint8_t)~_BV(MOTOR1_DIR_BIT);
      break;
    default:
      if (reverse) PORT_OF(MOTOR2_DIR_PORT) |= _BV(MOTOR2_DIR_BIT); else PORT_OF(MOTOR2_DIR_PORT) &= (uint8_t)~_BV(MOTOR2_DIR_BIT);
      break;
  }
}

void motors_zero(void) {
  uint8_t motor;
  for (motor = 0; motor < BOARD_WHEELS; ++motor) set_pwm(motor, 0);
}

void motors_set_enabled(uint8_t on) {
  motors_zero();
  enabled = on ? 1 : 0;
  if (enabled) PORT_OF(DRIVER_ENABLE_PORT) |= _BV(DRIVER_ENABLE_BIT); else PORT_OF(DRIVER_ENABLE_PORT) &= (uint8_t)~_BV(DRIVER_ENABLE_BIT);
}

uint8_t motors_enabled(void) { return enabled; }

void motors_set_duty(uint8_t motor, int16_t duty) {
  if (!enabled || motor >= BOARD_WHEELS) return;
  set_direction(motor, duty < 0);
  set_pwm(motor, pwm_steps(duty < 0 ? (uint16_t)(-(int32_t)duty) : (uint16_t)duty));
}
