/* The wide BVH's traversal with an AVX node test: the eight children of a
 * node in one test of 256-bit registers (bvh_wide.c does it with two SSE2
 * tests). This file alone is compiled with -mavx (host/render/module.cmake,
 * on x86 only, which then defines TB_BVH_AVX for the library), and its
 * functions are called only where the CPU has AVX (tb__bvhw_have_avx). The
 * lanes run tb__accel_slab_t's arithmetic as the SSE2 test does (AVX has no
 * fused multiply-add, and -ffp-contract=off holds for the whole project), so
 * both traversals visit the same nodes and give the same answers
 * (render_accel_cases compares them node by node and query by query). */
#include "host/render/accel_internal.h"

#if defined(__AVX__) && defined(TB_BVH_AVX)
#include <immintrin.h>

/* v, with its value unknown to the optimiser (see bvh_wide.c). */
static inline __m256 tb__f8_opaque(__m256 v)
{
    __asm__("" : "+x"(v));
    return v;
}

/* A query ray prepared for the AVX node test. */
typedef struct tb__wray {
    __m256 o[3], inv[3];                     /* broadcasts */
    __m256 sign, k, one, minus_inf, plus_inf; /* the test's constants, made once per ray */
    __m256 kn, kf;                           /* 1 - k and 1 + k: the widening factors of t >= 0 */
    size_t near[3], far[3];                  /* per axis, the byte offset in a node of the near and far planes' row */
    unsigned oct;                            /* the direction's octant (bit a: inv_d's sign bit along a) */
} tb__wray;

/* Lane a of v in all eight lanes. */
#define TB__F8_LANE(v, a) \
    _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_shuffle_ps(v, v, (a) * 0x55)), _mm_shuffle_ps(v, v, (a) * 0x55), 1)

static inline void tb__wray_init(tb__wray *r, const tb_ray *ray)
{
    /* The three reciprocals in one division (each lane rounds as 1.0f / d
     * does); 1 / d has the sign bit of d, so the plane choice need not wait
     * for it. */
    __m128 inv = _mm_div_ps(_mm_set1_ps(1.0f), _mm_setr_ps(ray->d.x, ray->d.y, ray->d.z, 1.0f));
    const float d[3] = {ray->d.x, ray->d.y, ray->d.z}, o[3] = {ray->o.x, ray->o.y, ray->o.z};
    r->oct = 0;
    for (unsigned a = 0; a < 3; a++) {
        unsigned neg = signbit(d[a]) != 0;
        r->near[a] = (2 * a + neg) * sizeof(((tb__bvhw_node *)0)->box[0]);
        r->far[a] = (2 * a + 1 - neg) * sizeof(((tb__bvhw_node *)0)->box[0]);
        r->oct |= neg << a;
        r->o[a] = _mm256_set1_ps(o[a]);
    }
    r->inv[0] = TB__F8_LANE(inv, 0);
    r->inv[1] = TB__F8_LANE(inv, 1);
    r->inv[2] = TB__F8_LANE(inv, 2);
    r->sign = tb__f8_opaque(_mm256_set1_ps(-0.0f));
    r->k = tb__f8_opaque(_mm256_set1_ps(2.0f * tb_gamma(3)));
    r->one = tb__f8_opaque(_mm256_set1_ps(1.0f));
    r->kn = tb__f8_opaque(_mm256_set1_ps(1.0f - 2.0f * tb_gamma(3)));
    r->kf = tb__f8_opaque(_mm256_set1_ps(1.0f + 2.0f * tb_gamma(3)));
    r->minus_inf = tb__f8_opaque(_mm256_set1_ps(-INFINITY));
    r->plus_inf = tb__f8_opaque(_mm256_set1_ps(INFINITY));
}

typedef __m256 tb__wvec;

static inline tb__wvec tb__wvec_set1(float x) { return _mm256_set1_ps(x); }

/* The eight children's slab tests at once: bvh_wide.c's tb__wtest4 on
 * eight lanes (the same operations; VMAXPS/VMINPS return the second operand
 * when either is NaN as MAXPS/MINPS do; _CMP_LE_OQ is CMPLEPS), with its
 * `full` widening or the short one for tmin >= 0. */
static inline __attribute__((always_inline)) unsigned tb__wtest(const tb__bvhw_node *nd, const tb__wray *r,
                                                                tb__wvec tmin, tb__wvec tmax, float tn[TB__BVHW],
                                                                bool full)
{
    const char *b = (const char *)nd;
    __m256 nx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps((const float *)(b + r->near[0])), r->o[0]), r->inv[0]);
    __m256 fx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps((const float *)(b + r->far[0])), r->o[0]), r->inv[0]);
    __m256 ny = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps((const float *)(b + r->near[1])), r->o[1]), r->inv[1]);
    __m256 fy = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps((const float *)(b + r->far[1])), r->o[1]), r->inv[1]);
    __m256 nz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps((const float *)(b + r->near[2])), r->o[2]), r->inv[2]);
    __m256 fz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps((const float *)(b + r->far[2])), r->o[2]), r->inv[2]);
    const __m256 sign = r->sign, k = r->k, one = r->one;
    __m256 n = _mm256_max_ps(nz, _mm256_max_ps(ny, _mm256_max_ps(nx, r->minus_inf)));
    __m256 f = _mm256_min_ps(fz, _mm256_min_ps(fy, _mm256_min_ps(fx, r->plus_inf)));
    if (full) {
        n = _mm256_mul_ps(n, _mm256_sub_ps(one, _mm256_or_ps(_mm256_and_ps(n, sign), k)));
        f = _mm256_mul_ps(f, _mm256_add_ps(one, _mm256_or_ps(_mm256_and_ps(f, sign), k)));
    } else {
        n = _mm256_mul_ps(n, r->kn);
        f = _mm256_mul_ps(f, r->kf);
    }
    tmin = _mm256_max_ps(n, tmin);
    tmax = _mm256_min_ps(f, tmax);
    _mm256_storeu_ps(tn, tmin);
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(tmin, tmax, _CMP_LE_OQ));
}

unsigned tb__bvhw_slab_test_avx(const tb__bvhw_node *nd, const tb_ray *ray, float tmin, float tmax,
                                float tnear[TB__BVHW])
{
    tb__wray r;
    tb__wray_init(&r, ray);
    return tb__wtest(nd, &r, tb__wvec_set1(tmin), tb__wvec_set1(tmax), tnear, !(tmin >= 0.0f));
}

#define TB__WFULL 0
#define TB__WNAME(name) name##_avx
#include "host/render/bvh_wide_traverse.inc"
#undef TB__WNAME
#undef TB__WFULL
#define TB__WFULL 1
#define TB__WNAME(name) name##_avx_full
#include "host/render/bvh_wide_traverse.inc"
#undef TB__WNAME
#undef TB__WFULL

#endif
