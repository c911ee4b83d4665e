/* Procedural textures (Perlin noise, fBm, turbulence, the box-filtered
 * checkerboard), the texture dispatch and bump mapping (texture.h,
 * docs/textures.md). */
#include "host/render/texture.h"

#include <math.h>
#include <string.h>

#include "util/math/float.h"
#include "util/stats/stats.h"

/* What a procedural pattern or bump map costs per hit (the cost model counts it: docs/predict.md). */
TB_STAT_COUNTER(tb__noise_octaves, "Pattern/noise octaves");

/* ---------------------------------------------------------------- noise */

/* Ken Perlin's permutation of 0..255 from his reference implementation of
 * improved noise (2002), so values match other implementations of it. */
static const unsigned char tb__perm[256] = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103,
    30,  69,  142, 8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,
    197, 62,  94,  252, 219, 203, 117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174,
    20,  125, 136, 171, 168, 68,  175, 74,  165, 71,  134, 139, 48,  27,  166, 77,  146, 158, 231,
    83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,  55,  46,  245, 40,  244, 102, 143,
    54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,  18,  169, 200, 196,
    135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250, 124,
    123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,
    182, 189, 28,  42,  223, 183, 170, 213, 119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101,
    155, 167, 43,  172, 9,   129, 22,  39,  253, 19,  98,  108, 110, 79,  113, 224, 232, 178, 185,
    112, 104, 218, 246, 97,  228, 251, 34,  242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,
    51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,  181, 199, 106, 157, 184, 84,  204, 176,
    115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114, 67,  29,  24,  72,  243,
    141, 128, 195, 78,  66,  215, 61,  156, 180,
};

static int tb__p(int i) { return tb__perm[i & 255]; }

const unsigned char *tb_noise_permutation(void) { return tb__perm; }

/* Quintic fade 6t^5 - 15t^4 + 10t^3: C2 across cells. */
static double tb__fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

/* Dot product of (x, y, z) with one of the 12 cube-edge gradients
 * (+-1, +-1, 0) and permutations, picked by the low 4 bits of h (4 of the 16
 * codes repeat gradients, as in Perlin's reference). */
static double tb__grad(int h, double x, double y, double z)
{
    h &= 15;
    double u = h < 8 ? x : y;
    double v = h < 4 ? y : (h == 12 || h == 14 ? x : z);
    return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

static double tb__lerp(double t, double a, double b) { return a + t * (b - a); }

double tb_noise3(double x, double y, double z)
{
    if (!(isfinite(x) && isfinite(y) && isfinite(z)))
        return 0.0;
    /* the lattice repeats every 256 cells: reduce first so that huge
     * coordinates keep their fraction's precision as far as double allows */
    double fx = floor(x), fy = floor(y), fz = floor(z);
    int X = (int)fmod(fx, 256.0), Y = (int)fmod(fy, 256.0), Z = (int)fmod(fz, 256.0);
    X &= 255;
    Y &= 255;
    Z &= 255;
    x -= fx;
    y -= fy;
    z -= fz;
    double u = tb__fade(x), v = tb__fade(y), w = tb__fade(z);
    int A = tb__p(X) + Y, AA = tb__p(A) + Z, AB = tb__p(A + 1) + Z;
    int B = tb__p(X + 1) + Y, BA = tb__p(B) + Z, BB = tb__p(B + 1) + Z;
    return tb__lerp(w,
                    tb__lerp(v, tb__lerp(u, tb__grad(tb__p(AA), x, y, z), tb__grad(tb__p(BA), x - 1, y, z)),
                             tb__lerp(u, tb__grad(tb__p(AB), x, y - 1, z), tb__grad(tb__p(BB), x - 1, y - 1, z))),
                    tb__lerp(v,
                             tb__lerp(u, tb__grad(tb__p(AA + 1), x, y, z - 1),
                                      tb__grad(tb__p(BA + 1), x - 1, y, z - 1)),
                             tb__lerp(u, tb__grad(tb__p(AB + 1), x, y - 1, z - 1),
                                      tb__grad(tb__p(BB + 1), x - 1, y - 1, z - 1))));
}

/* Lacunarity: the frequency ratio of successive octaves. */
#define TB__LACUNARITY 1.99

/* Octaves to sum for a footprint (pbrt's rule): frequency 2^i stays below
 * half the sampling rate while 2^i |dp| < 1/2, i.e. i < -1 - log2 |dp|. */
static double tb__octaves(tb_dvec3 dpdx, tb_dvec3 dpdy, int octaves)
{
    if (octaves < 0)
        octaves = 0;
    if (octaves > 32)
        octaves = 32;
    double len2 = fmax(tb_dvec3_length2(dpdx), tb_dvec3_length2(dpdy));
    if (!(len2 > 0.0) || !isfinite(len2))
        return octaves;
    double n = -1.0 - 0.5 * log2(len2);
    return n < 0.0 ? 0.0 : (n > octaves ? octaves : n);
}

static double tb__smoothstep(double a, double b, double x)
{
    double t = (x - a) / (b - a);
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    return t * t * (3.0 - 2.0 * t);
}

static double tb__octave_sum(tb_dvec3 p, tb_dvec3 dpdx, tb_dvec3 dpdy, double omega, int octaves, bool absolute)
{
    double n = tb__octaves(dpdx, dpdy, octaves);
    int ni = (int)floor(n);
    double sum = 0.0, freq = 1.0, amp = 1.0;
    for (int i = 0; i < ni; i++) {
        double v = tb_noise3(p.x * freq, p.y * freq, p.z * freq);
        sum += amp * (absolute ? fabs(v) : v);
        freq *= TB__LACUNARITY;
        amp *= omega;
    }
    /* the partial octave fades in rather than popping */
    double part = n - ni;
    tb_stat_add(&tb__noise_octaves, (uint64_t)ni + (part > 0.0 && ni < 32));
    if (part > 0.0 && ni < 32) {
        double v = tb_noise3(p.x * freq, p.y * freq, p.z * freq);
        sum += amp * tb__smoothstep(0.3, 0.7, part) * (absolute ? fabs(v) : v);
    }
    return sum;
}

double tb_fbm3(tb_dvec3 p, tb_dvec3 dpdx, tb_dvec3 dpdy, double omega, int octaves)
{
    return tb__octave_sum(p, dpdx, dpdy, omega, octaves, false);
}

double tb_turbulence3(tb_dvec3 p, tb_dvec3 dpdx, tb_dvec3 dpdy, double omega, int octaves)
{
    return tb__octave_sum(p, dpdx, dpdy, omega, octaves, true);
}

/* ---------------------------------------------------------------- checker */

/* Integral from 0 to x of the square wave that is 0 on [2k, 2k+1) and 1 on
 * [2k+1, 2k+2): floor(x/2) full periods plus the part of the current one. */
static double tb__square_integral(double x)
{
    double h = floor(x * 0.5);
    double r = x - 2.0 * h; /* in [0, 2) */
    return h + (r > 1.0 ? r - 1.0 : 0.0);
}

/* Fraction of [x0, x1] where floor(x) is odd. */
static double tb__odd_fraction(double x0, double x1)
{
    double w = x1 - x0;
    if (!(w > 1e-9 * (1.0 + fabs(x0)))) {
        double m = 0.5 * (x0 + x1);
        return fmod(fabs(floor(m)), 2.0) == 1.0 ? 1.0 : 0.0;
    }
    return (tb__square_integral(x1) - tb__square_integral(x0)) / w;
}

double tb_checker_box_average(double s0, double s1, double t0, double t1)
{
    if (s1 < s0) {
        double t = s0;
        s0 = s1;
        s1 = t;
    }
    if (t1 < t0) {
        double t = t0;
        t0 = t1;
        t1 = t;
    }
    /* odd squares are where exactly one of floor(s), floor(t) is odd; the box
     * is separable, so the average of that XOR is fs + ft - 2 fs ft */
    double fs = tb__odd_fraction(s0, s1), ft = tb__odd_fraction(t0, t1);
    return fs + ft - 2.0 * fs * ft;
}

double tb_checker3_box_average(double x0, double x1, double y0, double y1, double z0, double z1)
{
    /* odd cells have an odd number of odd coordinates: with e = 1 - 2 f per
     * axis (f the odd fraction, independent over the separable box), the
     * average of (-1)^(sum) is ex ey ez, so the odd share is (1 - ex ey ez) / 2 */
    double ex = 1.0 - 2.0 * tb__odd_fraction(fmin(x0, x1), fmax(x0, x1));
    double ey = 1.0 - 2.0 * tb__odd_fraction(fmin(y0, y1), fmax(y0, y1));
    double ez = 1.0 - 2.0 * tb__odd_fraction(fmin(z0, z1), fmax(z0, z1));
    return 0.5 * (1.0 - ex * ey * ez);
}

/* ---------------------------------------------------------------- textures */

static int tb__clamp_channels(int n)
{
    return n < 1 ? 1 : (n > TB_TEX_MAX_CHANNELS ? TB_TEX_MAX_CHANNELS : n);
}

static tb_texture tb__base(tb_texture_kind kind, int channels)
{
    tb_texture t;
    memset(&t, 0, sizeof t);
    t.kind = kind;
    t.channels = tb__clamp_channels(channels);
    t.su = 1.0f;
    t.sv = 1.0f;
    t.max_aniso = TB_TEX_MAX_ANISO_DEFAULT;
    return t;
}

tb_texture tb_texture_constant(int channels, const float *value)
{
    tb_texture t = tb__base(TB_TEXTURE_CONSTANT, channels);
    for (int c = 0; c < t.channels; c++)
        t.a[c] = value[c];
    return t;
}

tb_texture tb_texture_image(const tb_mipmap *mip, tb_tex_filter filter, tb_tex_wrap wrap)
{
    tb_texture t = tb__base(TB_TEXTURE_IMAGE, mip ? mip->channels : 1);
    t.mip = mip;
    t.filter = filter;
    t.wrap = wrap;
    return t;
}

tb_texture tb_texture_checker(int channels, const float *even, const float *odd, bool filtered)
{
    tb_texture t = tb__base(TB_TEXTURE_CHECKER, channels);
    for (int c = 0; c < t.channels; c++) {
        t.a[c] = even[c];
        t.b[c] = odd[c];
    }
    t.filtered = filtered;
    return t;
}

tb_texture tb_texture_noise(int channels, const float *lo, const float *hi, tb_noise_kind kind,
                            int octaves, float omega)
{
    tb_texture t = tb__base(TB_TEXTURE_NOISE, channels);
    for (int c = 0; c < t.channels; c++) {
        t.a[c] = lo[c];
        t.b[c] = hi[c];
    }
    t.noise = kind;
    t.octaves = octaves;
    t.omega = omega;
    return t;
}

static void tb__blend(const tb_texture *t, double f, float *out)
{
    for (int c = 0; c < t->channels; c++)
        out[c] = (float)((double)t->a[c] + f * ((double)t->b[c] - (double)t->a[c]));
}

void tb_texture_eval(const tb_texture *t, const tb_tex_query *q, float *out)
{
    /* the mapping, and the footprint through it */
    double s = (double)t->su * q->u + t->ou, r = (double)t->sv * q->v + t->ov;
    tb_tex_footprint fp = {t->su * q->fp.dudx, t->sv * q->fp.dvdx, t->su * q->fp.dudy, t->sv * q->fp.dvdy};
    switch (t->kind) {
    case TB_TEXTURE_CONSTANT:
        for (int c = 0; c < t->channels; c++)
            out[c] = t->a[c];
        return;
    case TB_TEXTURE_IMAGE:
        if (!t->mip) {
            for (int c = 0; c < t->channels; c++)
                out[c] = 0.0f;
            return;
        }
        tb_mipmap_lookup(t->mip, t->filter, (float)s, (float)r, &fp, t->wrap, t->max_aniso, out);
        return;
    case TB_TEXTURE_CHECKER: {
        double f;
        if (t->solid) {
            /* the box spanned by the pixel's change of the point, in cells */
            tb_dvec3 c = tb_dvec3_scale(tb_vec3_to_d(q->p), t->su);
            tb_dvec3 h = {0.0, 0.0, 0.0};
            if (t->filtered)
                h = tb_dvec3_scale(tb_dvec3_add(tb_dvec3_abs(tb_vec3_to_d(q->dpdx)), tb_dvec3_abs(tb_vec3_to_d(q->dpdy))),
                                   0.5 * fabs((double)t->su));
            f = tb_checker3_box_average(c.x - h.x, c.x + h.x, c.y - h.y, c.y + h.y, c.z - h.z, c.z + h.z);
        } else if (t->filtered) {
            /* the bounding box of the pixel's footprint parallelogram */
            double hs = 0.5 * (fabs((double)fp.dudx) + fabs((double)fp.dudy));
            double ht = 0.5 * (fabs((double)fp.dvdx) + fabs((double)fp.dvdy));
            f = tb_checker_box_average(s - hs, s + hs, r - ht, r + ht);
        } else {
            f = tb_checker_box_average(s, s, r, r);
        }
        tb__blend(t, f, out);
        return;
    }
    case TB_TEXTURE_NOISE: {
        tb_dvec3 p, dx, dy;
        if (t->solid) {
            p = tb_dvec3_scale(tb_vec3_to_d(q->p), t->su);
            dx = tb_dvec3_scale(tb_vec3_to_d(q->dpdx), t->su);
            dy = tb_dvec3_scale(tb_vec3_to_d(q->dpdy), t->su);
        } else {
            p = tb_dvec3_make(s, r, 0.0);
            dx = tb_dvec3_make(fp.dudx, fp.dvdx, 0.0);
            dy = tb_dvec3_make(fp.dudy, fp.dvdy, 0.0);
        }
        double f = t->noise == TB_NOISE_TURBULENCE ? tb_turbulence3(p, dx, dy, t->omega, t->octaves)
                                                   : 0.5 + 0.5 * tb_fbm3(p, dx, dy, t->omega, t->octaves);
        tb__blend(t, tb_clamp(f, 0.0, 1.0), out);
        return;
    }
    }
    for (int c = 0; c < t->channels; c++)
        out[c] = 0.0f;
}

float tb_texture_eval1(const tb_texture *t, const tb_tex_query *q)
{
    float out[TB_TEX_MAX_CHANNELS];
    tb_texture_eval(t, q, out);
    return out[0];
}

/* ---------------------------------------------------------------- bump mapping */

/* Step used when there is no footprint: about a texel of a 2K texture. */
#define TB__BUMP_DEFAULT_STEP (1.0 / 2048.0)

bool tb_bump_map(const tb_texture *height, float scale, const tb_bump_geom *g, tb_vec3 *n_out,
                 tb_vec3 *dpdu_out, tb_vec3 *dpdv_out)
{
    tb_dvec3 n = tb_vec3_to_d(g->n), dpdu = tb_vec3_to_d(g->dpdu), dpdv = tb_vec3_to_d(g->dpdv);
    double du = 0.5 * (fabs((double)g->fp.dudx) + fabs((double)g->fp.dudy));
    double dv = 0.5 * (fabs((double)g->fp.dvdx) + fabs((double)g->fp.dvdy));
    if (!(du > 0.0) || !isfinite(du))
        du = TB__BUMP_DEFAULT_STEP;
    if (!(dv > 0.0) || !isfinite(dv))
        dv = TB__BUMP_DEFAULT_STEP;
    /* the three height lookups share the footprint; the shifted ones move the
     * point along the tangent as well (for solid textures) */
    tb_tex_query q = {.u = g->u, .v = g->v, .fp = g->fp, .p = g->p, .dpdx = g->dpdx, .dpdy = g->dpdy};
    double h = (double)scale * tb_texture_eval1(height, &q);
    tb_tex_query qu = q, qv = q;
    bool tsp = g->tp_du.x != 0.0f || g->tp_du.y != 0.0f || g->tp_du.z != 0.0f || g->tp_dv.x != 0.0f ||
               g->tp_dv.y != 0.0f || g->tp_dv.z != 0.0f;
    tb_dvec3 tdu = tsp ? tb_vec3_to_d(g->tp_du) : dpdu, tdv = tsp ? tb_vec3_to_d(g->tp_dv) : dpdv;
    qu.u = (float)((double)g->u + du);
    qu.p = tb_dvec3_to_f(tb_dvec3_add(tb_vec3_to_d(g->p), tb_dvec3_scale(tdu, du)));
    qv.v = (float)((double)g->v + dv);
    qv.p = tb_dvec3_to_f(tb_dvec3_add(tb_vec3_to_d(g->p), tb_dvec3_scale(tdv, dv)));
    /* the actual steps after rounding to float, so a linear height field
     * gives its exact slope */
    double du_eff = (double)qu.u - (double)g->u, dv_eff = (double)qv.v - (double)g->v;
    if (du_eff == 0.0 || dv_eff == 0.0) {
        if (n_out)
            *n_out = g->n;
        return false;
    }
    double hu = (double)scale * tb_texture_eval1(height, &qu);
    double hv = (double)scale * tb_texture_eval1(height, &qv);
    tb_dvec3 pu = tb_dvec3_add(tb_dvec3_add(dpdu, tb_dvec3_scale(n, (hu - h) / du_eff)),
                               tb_dvec3_scale(tb_vec3_to_d(g->dndu), h));
    tb_dvec3 pv = tb_dvec3_add(tb_dvec3_add(dpdv, tb_dvec3_scale(n, (hv - h) / dv_eff)),
                               tb_dvec3_scale(tb_vec3_to_d(g->dndv), h));
    tb_dvec3 nn = tb_dvec3_cross(pu, pv);
    double len = tb_dvec3_length(nn);
    if (!(len > 0.0) || !isfinite(len)) {
        if (n_out)
            *n_out = g->n;
        return false;
    }
    nn = tb_dvec3_scale(nn, 1.0 / len);
    if (tb_dvec3_dot(nn, n) < 0.0)
        nn = tb_dvec3_neg(nn);
    if (n_out)
        *n_out = tb_dvec3_to_f(nn);
    if (dpdu_out)
        *dpdu_out = tb_dvec3_to_f(pu);
    if (dpdv_out)
        *dpdv_out = tb_dvec3_to_f(pv);
    return true;
}
