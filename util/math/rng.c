#include "util/math/rng.h"

#define TB__PCG_MULT 6364136223846793005ull

void tb_rng_seed(tb_rng *r, uint64_t seed, uint64_t stream)
{
    r->state = 0u;
    r->inc = (stream << 1u) | 1u;
    tb_rng_u32(r);
    r->state += seed;
    tb_rng_u32(r);
}

uint32_t tb_rng_u32(tb_rng *r)
{
    uint64_t old = r->state;
    r->state = old * TB__PCG_MULT + r->inc;
    uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31u));
}

uint32_t tb_rng_below(tb_rng *r, uint32_t bound)
{
    /* Rejection threshold from the PCG reference: 2^32 mod bound. */
    uint32_t threshold = (uint32_t)(-bound) % bound;
    for (;;) {
        uint32_t x = tb_rng_u32(r);
        if (x >= threshold)
            return x % bound;
    }
}

float tb_rng_float(tb_rng *r)
{
    return (float)(tb_rng_u32(r) >> 8) * 0x1p-24f;
}

double tb_rng_double(tb_rng *r)
{
    uint64_t hi = tb_rng_u32(r) >> 5, lo = tb_rng_u32(r) >> 6;
    return (double)(hi * 67108864ull + lo) * 0x1p-53;
}
