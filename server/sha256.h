/* sha256.h - SHA-256 (FIPS 180-4) for token hashes, idempotency fingerprints and
 * result ETags. Small and dependency-free so the daemon links only what the
 * Makefile names. Thread-safe: all state lives in the context. */
#ifndef QDCD_SHA256_H
#define QDCD_SHA256_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
    uint32_t h[8];
    uint64_t len; /* bytes hashed so far */
    uint8_t buf[64];
    size_t nbuf;
} sha256_ctx;

void sha256_init(sha256_ctx *c);
void sha256_update(sha256_ctx *c, const void *data, size_t len);
void sha256_final(sha256_ctx *c, uint8_t out[32]);
/* One-shot, hex (64 chars + NUL). */
void sha256_hex(const void *data, size_t len, char out[65]);
void sha256_to_hex(const uint8_t dig[32], char out[65]);
/* Hash a whole file into hex; returns 0 or -1 (errno set). */
int sha256_file_hex(const char *path, char out[65]);

#endif
