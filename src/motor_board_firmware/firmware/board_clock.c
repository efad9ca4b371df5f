#include "board_clock.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "board_config.h"
#include "motors.h"

static volatile uint32_t board_ms;
static volatile uint16_t ms_since_command;
static volatile uint8_t command_seen;    /* no command since power-up: nothing to time out */
static volatile uint8_t watchdog_stopped;

void board_clock_init(void) {
  /* Timer 1, CTC on OCR1A, clock / 8: 2000 counts per ms. */
  TCCR1A = 0;
  TCCR1B = _BV(WGM12) | _BV(CS11);
  OCR1A = (uint16_t)(F_CPU / 8u / TICK_HZ - 1u);
  TIMSK1 = _BV(OCIE1A);
}

ISR(TIMER1_COMPA_vect) {
  ++board_ms;
  if (!command_seen || watchdog_stopped) return;
  if (++ms_since_command >= MP_BOARD_WATCHDOG_MS) {
    motors_zero();
    watchdog_stopped = 1;
  }
}

uint32_t board_time_ms_locked(void) { return board_ms; }

void board_clock_command_received_locked(void) {
  ms_since_command = 0;
  command_seen = 1;
  watchdog_stopped = 0;
}

uint8_t board_clock_watchdog_stopped(void) { return watchdog_stopped; }
