/* PCG32 random numbers (O'Neill 2014): small state, reproducible streams, so
 * renderers and property tests give the same numbers for the same seed on any
 * thread count (each task seeds its own stream). */
#ifndef TB_UTIL_MATH_RNG_H
#define TB_UTIL_MATH_RNG_H

#include <stdint.h>

/* One PCG32 generator. */
typedef struct tb_rng {
    uint64_t state;
    uint64_t inc; /* stream selector, always odd */
} tb_rng;

/* Seeds `r` with `seed` on stream `stream` (independent sequences per stream). */
void tb_rng_seed(tb_rng *r, uint64_t seed, uint64_t stream);

/* PCG32's multiplier. */
#define TB_RNG_PCG_MULT 6364136223846793005ull

/* Next uniformly distributed 32-bit integer (inline: several calls per
 * light sample). */
static inline uint32_t tb_rng_u32(tb_rng *r)
{
    uint64_t old = r->state;
    r->state = old * TB_RNG_PCG_MULT + r->inc;
    uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31u));
}

/* Uniform integer in [0, bound), without modulo bias; bound > 0. */
uint32_t tb_rng_below(tb_rng *r, uint32_t bound);

/* Uniform float in [0, 1): 24 random bits, never 1.0f. */
static inline float tb_rng_float(tb_rng *r)
{
    return (float)(tb_rng_u32(r) >> 8) * 0x1p-24f;
}

/* Uniform double in [0, 1): 53 random bits. */
double tb_rng_double(tb_rng *r);

#endif
