#include "serial.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "board_config.h"

static volatile uint8_t rx_ring[SERIAL_RX_RING];
static volatile uint8_t rx_head, rx_tail; /* head: next write (ISR), tail: next read (main) */
static volatile uint8_t tx_ring[SERIAL_TX_RING];
static volatile uint8_t tx_head, tx_tail;
volatile uint16_t serial_rx_dropped;
volatile uint16_t serial_tx_dropped;

void serial_init(void) {
  const uint16_t ubrr = (uint16_t)((F_CPU + 4u * BOARD_BAUD) / (8u * BOARD_BAUD) - 1u); /* double speed */
  UCSR0A = _BV(U2X0); /* before the baud divisor: simavr derives its byte time when UBRR0L is written */
  UBRR0H = (uint8_t)(ubrr >> 8);
  UBRR0L = (uint8_t)ubrr;
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
  UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
}

ISR(USART_RX_vect) {
  const uint8_t status = UCSR0A;
  const uint8_t byte = UDR0;
  const uint8_t next = (uint8_t)((rx_head + 1u) & (SERIAL_RX_RING - 1u));
  if ((status & _BV(FE0)) || next == rx_tail) {
    ++serial_rx_dropped;
    return;
  }
  rx_ring[rx_head] = byte;
  rx_head = next;
}

ISR(USART_UDRE_vect) {
  if (tx_head == tx_tail) {
    UCSR0B &= (uint8_t)~_BV(UDRIE0);
    return;
  }
  UDR0 = tx_ring[tx_tail];
  tx_tail = (uint8_t)((tx_tail + 1u) & (SERIAL_TX_RING - 1u));
}

uint8_t serial_rx_empty(void) { return rx_head == rx_tail; }

uint8_t serial_read(uint8_t* out, uint8_t max) {
  uint8_t n = 0;
  while (n < max && rx_tail != rx_head) {
    out[n++] = rx_ring[rx_tail];
    rx_tail = (uint8_t)((rx_tail + 1u) & (SERIAL_RX_RING - 1u));
  }
  return n;
}

uint8_t serial_write(const uint8_t* data, uint8_t n) {
  const uint8_t used = (uint8_t)((tx_head - tx_tail) & (SERIAL_TX_RING - 1u));
  uint8_t i;
  if ((uint16_t)used + n > SERIAL_TX_RING - 1u) {
    ++serial_tx_dropped;
    return 0;
  }
  for (i = 0; i < n; ++i) {
    tx_ring[tx_head] = data[i];
    tx_head = (uint8_t)((tx_head + 1u) & (SERIAL_TX_RING - 1u));
  }
  UCSR0B |= _BV(UDRIE0);
  return 1;
}
