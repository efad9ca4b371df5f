/* The motor board protocol's one home: frame layout, message ids, payload layouts, status and fault
 * bits, limits, CRC-32C and the receivers' stream decoder. Plain C99 that is also valid C++17 and
 * needs nothing but <stdint.h> and <stddef.h>, so that the host driver (omni_base's motor_protocol.h
 * wraps it), the fake board and the AVR firmware (src/motor_board_firmware) compile the same text.
 * The protocol is specified for firmware authors in src/omni_base/README.md, "Motor board protocol".
 *
 * Frame: 0xA5 0x5A | type (u8) | length N (u8, 0..MP_MAX_PAYLOAD) | payload (N bytes) | CRC-32C (u32 LE)
 * The CRC covers type, length and payload. Multi-byte fields are little-endian. */
#ifndef OMNI_BASE_MOTOR_WIRE_H
#define OMNI_BASE_MOTOR_WIRE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Frame layout and limits ---- */
#define MP_START1 0xA5u
#define MP_START2 0x5Au
#define MP_HEADER_SIZE 4u  /* start1, start2, type, length */
#define MP_CRC_SIZE 4u
#define MP_MAX_PAYLOAD 64u
#define MP_MAX_FRAME (MP_HEADER_SIZE + MP_MAX_PAYLOAD + MP_CRC_SIZE)
#define MP_MAX_WHEELS 8u
#define MP_DUTY_FULL_SCALE 10000   /* duty in 1/10000 of the supply; |duty| > this makes a frame invalid */
#define MP_BOARD_WATCHDOG_MS 250u  /* no valid command this long: the board stops the motors */
#define MP_DEFAULT_BAUD 115200UL   /* 8N1, no flow control */

/* ---- Message ids ---- */
#define MP_TYPE_SET_DUTY 0x01u /* host -> board */
#define MP_TYPE_ENABLE 0x02u   /* host -> board */
#define MP_TYPE_STATE 0x81u    /* board -> host: one per valid SET_DUTY or ENABLE */

/* ---- Payload layouts (byte offsets) ---- */
/* SET_DUTY: u8 sequence, u8 n, n x i16 duty */
#define MP_SET_DUTY_SEQUENCE 0u
#define MP_SET_DUTY_COUNT 1u
#define MP_SET_DUTY_DUTIES 2u
#define MP_SET_DUTY_SIZE(n) (2u + 2u * (unsigned)(n))
/* ENABLE: u8 sequence, u8 enable (0 = brake and unpower, 1 = drive) */
#define MP_ENABLE_SEQUENCE 0u
#define MP_ENABLE_FLAG 1u
#define MP_ENABLE_SIZE 2u
/* STATE: u8 sequence (of the command answered), u8 status, u8 faults, u8 n, n x i32 counts, u32 board ms */
#define MP_STATE_SEQUENCE 0u
#define MP_STATE_STATUS 1u
#define MP_STATE_FAULTS 2u
#define MP_STATE_COUNT 3u
#define MP_STATE_COUNTS 4u
#define MP_STATE_TIME(n) (4u + 4u * (unsigned)(n))
#define MP_STATE_SIZE(n) (8u + 4u * (unsigned)(n))

/* STATE status bits */
#define MP_STATUS_ENABLED 0x01u          /* motors enabled (the last ENABLE said 1) */
#define MP_STATUS_WATCHDOG_STOPPED 0x02u /* the board stopped the motors: no valid command for 250 ms */
#define MP_STATUS_FAULT 0x04u            /* see the fault bits */
/* STATE fault bits */
#define MP_FAULT_STALL 0x01u
#define MP_FAULT_OVER_CURRENT 0x02u
#define MP_FAULT_UNDER_VOLTAGE 0x04u

/* ---- Little-endian fields ---- */
static inline uint16_t mp_get_u16le(const uint8_t* p) { return (uint16_t)(p[0] | ((uint16_t)p[1] << 8)); }
static inline uint32_t mp_get_u32le(const uint8_t* p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline void mp_put_u16le(uint8_t* p, uint16_t v) {
  p[0] = (uint8_t)(v & 0xFFu);
  p[1] = (uint8_t)(v >> 8);
}
static inline void mp_put_u32le(uint8_t* p, uint32_t v) {
  p[0] = (uint8_t)(v & 0xFFu);
  p[1] = (uint8_t)((v >> 8) & 0xFFu);
  p[2] = (uint8_t)((v >> 16) & 0xFFu);
  p[3] = (uint8_t)(v >> 24);
}

/* ---- CRC-32C (Castagnoli): reflected polynomial 0x82F63B78, init and final XOR 0xFFFFFFFF; the check
 * value of ASCII "123456789" is 0xE3069283. Bitwise: frames are at most 72 bytes, and a table would cost
 * the AVR 1 KB. ---- */
static inline uint32_t mp_crc32c(const uint8_t* data, size_t size) {
  uint32_t crc = 0xFFFFFFFFu;
  size_t i;
  int bit;
  for (i = 0; i < size; ++i) {
    crc ^= data[i];
    for (bit = 0; bit < 8; ++bit) crc = (crc & 1u) ? (crc >> 1) ^ 0x82F63B78u : crc >> 1;
  }
  return crc ^ 0xFFFFFFFFu;
}

/* Writes a whole frame (header, payload, CRC) to out, which must hold length + 8 bytes. Returns its
 * size, or 0 for a payload over MP_MAX_PAYLOAD (nothing written). */
static inline size_t mp_encode_frame(uint8_t* out, uint8_t type, const uint8_t* payload, size_t length) {
  size_t i;
  if (length > MP_MAX_PAYLOAD) return 0;
  out[0] = (uint8_t)MP_START1;
  out[1] = (uint8_t)MP_START2;
  out[2] = type;
  out[3] = (uint8_t)length;
  for (i = 0; i < length; ++i) out[MP_HEADER_SIZE + i] = payload[i];
  mp_put_u32le(out + MP_HEADER_SIZE + length, mp_crc32c(out + 2, 2u + length));
  return MP_HEADER_SIZE + length + MP_CRC_SIZE;
}

/* ---- Stream decoder (both ends) ----
 * Resynchronises by scanning for 0xA5 0x5A; after a bad CRC or a length over 64 it resumes the scan one
 * byte after the false start. A false start can also look valid (its CRC matching by chance) or announce
 * a length that runs past the bytes received so far; in both cases a complete valid frame that starts
 * inside its span wins, and a valid candidate is held back while a whole header inside it announces a
 * frame that has not fully arrived. What is kept between calls never exceeds 142 bytes (a held-back
 * candidate of at most 72 and the incomplete frame inside it), so a fixed buffer of two frames holds it
 * and the result does not depend on how the stream is split into calls. */
#define MP_DECODER_CAPACITY (2u * MP_MAX_FRAME)

typedef struct {
  uint8_t buf[MP_DECODER_CAPACITY];
  uint8_t size;  /* bytes held */
  uint8_t pos;   /* first byte not consumed yet */
  uint32_t frames;
  uint32_t crc_errors;
  uint32_t garbage_bytes;
  uint32_t length_errors;
  uint32_t false_starts; /* candidates overruled by a valid frame inside them */
} mp_decoder;

/* A decoded frame; payload points into the decoder and stays valid until the next mp_decoder_put. */
typedef struct {
  uint8_t type;
  uint8_t length;
  const uint8_t* payload;
} mp_frame;

static inline void mp_decoder_init(mp_decoder* d) {
  d->size = 0;
  d->pos = 0;
  d->frames = d->crc_errors = d->garbage_bytes = d->length_errors = d->false_starts = 0;
}

/* Total size of the frame whose sane header (start bytes, length <= 64) is at p, else 0. */
static inline uint8_t mp_decoder_frame_total_at_(const mp_decoder* d, uint8_t p) {
  if (d->size - p < (int)MP_HEADER_SIZE || d->buf[p] != MP_START1 || d->buf[p + 1] != MP_START2) return 0;
  if (d->buf[p + 3] > MP_MAX_PAYLOAD) return 0;
  return (uint8_t)(MP_HEADER_SIZE + d->buf[p + 3] + MP_CRC_SIZE);
}

static inline int mp_decoder_crc_valid_at_(const mp_decoder* d, uint8_t p, uint8_t total) {
  return mp_crc32c(&d->buf[p + 2], (size_t)total - 2u - MP_CRC_SIZE) == mp_get_u32le(&d->buf[p + total - MP_CRC_SIZE]);
}

/* Where a complete frame with a valid CRC starts in [from, to), if anywhere (returns 1 and sets *at). */
static inline int mp_decoder_valid_frame_in_(const mp_decoder* d, uint8_t from, uint8_t to, uint8_t* at) {
  uint8_t q;
  for (q = from; q < to; ++q) {
    const uint8_t total = mp_decoder_frame_total_at_(d, q);
    if (total != 0 && d->size - q >= total && mp_decoder_crc_valid_at_(d, q, total)) {
      *at = q;
      return 1;
    }
  }
  return 0;
}

/* A whole header in [from, to) whose frame is not complete yet. Only a whole, sane header counts: a start
 * sequence in the last bytes of a good frame must not hold it back (the sender may have nothing more). */
static inline int mp_decoder_incomplete_frame_in_(const mp_decoder* d, uint8_t from, uint8_t to) {
  uint8_t q;
  for (q = from; q < to; ++q) {
    const uint8_t total = mp_decoder_frame_total_at_(d, q);
    if (total != 0 && d->size - q < total) return 1;
  }
  return 0;
}

/* Appends up to n bytes and returns how many it took (call mp_decoder_next until it returns 0, then put
 * the rest). */
static inline size_t mp_decoder_put(mp_decoder* d, const uint8_t* data, size_t n) {
  size_t i, room;
  if (d->pos == 0 && d->size == MP_DECODER_CAPACITY && n > 0) {
    /* Cannot happen (at most 142 bytes are kept), but a full buffer must never stop the stream. */
    ++d->garbage_bytes;
    d->pos = 1;
  }
  if (d->pos > 0) { /* drop what is consumed */
    for (i = d->pos; i < d->size; ++i) d->buf[i - d->pos] = d->buf[i];
    d->size = (uint8_t)(d->size - d->pos);
    d->pos = 0;
  }
  room = MP_DECODER_CAPACITY - d->size;
  if (n > room) n = room;
  for (i = 0; i < n; ++i) d->buf[d->size + i] = data[i];
  d->size = (uint8_t)(d->size + n);
  return n;
}

/* The next complete, valid frame in what was put: returns 1 and fills *frame, or 0 when more bytes are
 * needed. */
static inline int mp_decoder_next(mp_decoder* d, mp_frame* frame) {
  for (;;) {
    uint8_t start = d->pos, total, span_end, inner;
    /* Find the start sequence; everything before it is garbage. */
    while (start + 1 < d->size && !(d->buf[start] == MP_START1 && d->buf[start + 1] == MP_START2)) ++start;
    if (start + 1 >= d->size) {
      /* Keep a trailing 0xA5: it may be the first half of a start sequence. */
      const uint8_t keep_from =
          (d->size > 0 && d->buf[d->size - 1] == MP_START1 && start < d->size) ? (uint8_t)(d->size - 1) : d->size;
      d->garbage_bytes += (uint32_t)(keep_from - d->pos);
      d->pos = keep_from;
      return 0;
    }
    d->garbage_bytes += (uint32_t)(start - d->pos);
    d->pos = start;
    if (d->size - d->pos < (int)MP_HEADER_SIZE) return 0; /* wait for the header */
    total = mp_decoder_frame_total_at_(d, d->pos);
    if (total == 0) { /* a length over 64: a false start, search again from the next byte */
      ++d->length_errors;
      ++d->garbage_bytes;
      ++d->pos;
      continue;
    }
    span_end = (uint8_t)((d->size - d->pos < total) ? d->size : d->pos + total);
    /* A complete valid frame inside this candidate's span makes the candidate a false start. */
    if (mp_decoder_valid_frame_in_(d, (uint8_t)(d->pos + 1), span_end, &inner)) {
      ++d->false_starts;
      d->garbage_bytes += (uint32_t)(inner - d->pos);
      d->pos = inner;
      continue;
    }
    if (d->size - d->pos < total) return 0; /* wait for the rest */
    if (!mp_decoder_crc_valid_at_(d, d->pos, total)) {
      ++d->crc_errors;
      ++d->garbage_bytes;
      ++d->pos;
      continue;
    }
    /* Valid, but a frame starting inside it is still arriving and could overrule it: wait. */
    if (mp_decoder_incomplete_frame_in_(d, (uint8_t)(d->pos + 1), (uint8_t)(d->pos + total))) return 0;
    frame->type = d->buf[d->pos + 2];
    frame->length = d->buf[d->pos + 3];
    frame->payload = &d->buf[d->pos + MP_HEADER_SIZE];
    ++d->frames;
    d->pos = (uint8_t)(d->pos + total);
    return 1;
  }
}

#ifdef __cplusplus
}  /* extern "C" */
#endif

#endif /* OMNI_BASE_MOTOR_WIRE_H */
