#include "util/math/rng.h"

/* tb_rng_u32 and tb_rng_float are inline in rng.h. */

void tb_rng_seed(tb_rng *r, uint64_t seed, uint64_t stream)
{
    r->state = 0u;
    r->inc = (stream << 1u) | 1u;
    tb_rng_u32(r);
    r->state += seed;
    tb_rng_u32(r);
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

double tb_rng_double(tb_rng *r)
{
    uint64_t hi = tb_rng_u32(r) >> 5, lo = tb_rng_u32(r) >> 6;
    return (double)(hi * 67108864ull + lo) * 0x1p-53;
}
