/* The host link's UART (8N1) with interrupt-driven receive and transmit rings. */
#ifndef MOTOR_BOARD_SERIAL_H
#define MOTOR_BOARD_SERIAL_H

#include <stddef.h>
#include <stdint.h>

void serial_init(void);
/* Moves up to max received bytes to out; returns how many. */
uint8_t serial_read(uint8_t* out, uint8_t max);
uint8_t serial_rx_empty(void);
/* Queues all n bytes, or none when the ring lacks room (returns 0): never waits for the line. */
uint8_t serial_write(const uint8_t* data, uint8_t n);

/* Bytes lost because the receive ring was full, or with a framing error. Read by the harness. */
extern volatile uint16_t serial_rx_dropped;
extern volatile uint16_t serial_tx_dropped;

#endif
