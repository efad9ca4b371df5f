/* The motor board's firmware (ATmega328P, 16 MHz): the board side of omni_base's motor protocol for the
 * three-wheel omni base. Pins and timing: board_config.h. Build and flash: README.md of this package.
 *
 * Interrupts do the timing-critical work: encoder edges (pin change), the 1 kHz board clock with the
 * command watchdog (timer 1), the serial rings. The main loop decodes received bytes, applies commands,
 * queues replies and sleeps until the next interrupt; the hardware watchdog resets the MCU if it stops. */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>

#include "board_clock.h"
#include "board_config.h"
#include "encoders.h"
#include "link.h"
#include "motors.h"
#include "serial.h"

#define STACK_PAINT 0xC5u

/* MCUSR at the last reset (why the board restarted); kept out of .bss so the start-up code leaves it. */
uint8_t reset_flags __attribute__((section(".noinit")));
extern uint8_t __heap_start;

/* Runs before .data and .bss are set up, with the stack still empty: stops a watchdog left running by a
 * watchdog reset (else it would reset again during start-up), and paints the free RAM so that the peak
 * stack use can be read off it (the harness does, at the lowest overwritten byte). */
void early_init(void) __attribute__((naked, used, section(".init3")));
void early_init(void) {
  uint8_t* p;
  reset_flags = MCUSR;
  MCUSR = 0;
  wdt_disable();
  for (p = &__heap_start; p <= (uint8_t*)RAMEND; ++p) *p = STACK_PAINT;
}

int main(void) {
  motors_init(); /* first: the bridges in standby at zero duty */
  DDR_OF(BUSY_PORT_LETTER) |= _BV(BUSY_BIT);
  encoders_init();
  board_clock_init();
  serial_init();
  link_init();
  wdt_enable(HARDWARE_WATCHDOG);
  set_sleep_mode(SLEEP_MODE_IDLE);
  sei();
  for (;;) {
    wdt_reset();
    PORT_OF(BUSY_PORT_LETTER) |= _BV(BUSY_BIT);
    link_poll();
    PORT_OF(BUSY_PORT_LETTER) &= (uint8_t)~_BV(BUSY_BIT);
    cli();
    if (serial_rx_empty()) { /* sleep until the next interrupt; sei takes effect after sleep is entered */
      sleep_enable();
      sei();
      sleep_cpu();
      sleep_disable();
    }
    sei();
  }
}
