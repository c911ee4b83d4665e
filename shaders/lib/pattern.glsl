// Procedural patterns: the GLSL twins of texture_proc.c's tb_noise3
// (Perlin's improved noise, his permutation), tb_fbm3 (octaves chosen from
// the footprint, pbrt's rule, the partial octave faded in),
// tb_checker_box_average and tb_checker3_box_average (the checkerboard
// box-filtered over the footprint's bounding box). The C code works in
// double, these in float; tests/gpu (test_gpu_kernels.c, k_shading) checks
// them against the C functions (tolerances in docs/gpu.md, "GLSL routine
// library").
#ifndef TB_LIB_PATTERN_GLSL
#define TB_LIB_PATTERN_GLSL

// The includer defines `int tb_perm(int i)`: Perlin's permutation
// (tb_noise_permutation()) at i & 255. The shaders read it from a buffer: a
// constant array indexed per lane made lavapipe's compile of the shade
// kernel run for minutes (one copy of the table per inlined lookup).

float tb_fade(float t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

// The dot product with one of the 12 cube-edge gradients picked by h's low 4 bits.
float tb_grad(int h, float x, float y, float z)
{
    h &= 15;
    float u = h < 8 ? x : y;
    float v = h < 4 ? y : (h == 12 || h == 14 ? x : z);
    return ((h & 1) != 0 ? -u : u) + ((h & 2) != 0 ? -v : v);
}

// a + t (b - a), as C's tb__lerp (GLSL's mix rounds differently).
float tb_lerp(float t, float a, float b) { return a + t * (b - a); }

// tb_noise3: 0 for a non-finite point.
float tb_noise3(vec3 q)
{
    if (any(isinf(q)) || any(isnan(q)))
        return 0.0;
    vec3 f = floor(q);
    // C's fmod keeps the sign, GLSL's mod does not; both agree after & 255
    ivec3 I = ivec3(mod(f, 256.0)) & 255;
    q -= f;
    float u = tb_fade(q.x), v = tb_fade(q.y), w = tb_fade(q.z);
    float x = q.x, y = q.y, z = q.z;
    int A = tb_perm(I.x) + I.y, AA = tb_perm(A) + I.z, AB = tb_perm(A + 1) + I.z;
    int B = tb_perm(I.x + 1) + I.y, BA = tb_perm(B) + I.z, BB = tb_perm(B + 1) + I.z;
    return tb_lerp(w,
                    tb_lerp(v, tb_lerp(u, tb_grad(tb_perm(AA), x, y, z), tb_grad(tb_perm(BA), x - 1.0, y, z)),
                             tb_lerp(u, tb_grad(tb_perm(AB), x, y - 1.0, z),
                                      tb_grad(tb_perm(BB), x - 1.0, y - 1.0, z))),
                    tb_lerp(v,
                             tb_lerp(u, tb_grad(tb_perm(AA + 1), x, y, z - 1.0),
                                      tb_grad(tb_perm(BA + 1), x - 1.0, y, z - 1.0)),
                             tb_lerp(u, tb_grad(tb_perm(AB + 1), x, y - 1.0, z - 1.0),
                                      tb_grad(tb_perm(BB + 1), x - 1.0, y - 1.0, z - 1.0))));
}

// Octaves of fBm for a footprint (tb__octaves).
float tb_octaves(vec3 dpdx, vec3 dpdy, int octaves)
{
    octaves = clamp(octaves, 0, 32);
    float len2 = max(dot(dpdx, dpdx), dot(dpdy, dpdy));
    if (!(len2 > 0.0) || isinf(len2))
        return float(octaves);
    float n = -1.0 - 0.5 * log2(len2);
    return n < 0.0 ? 0.0 : min(n, float(octaves));
}

// tb_fbm3 with omega and lacunarity 1.99.
float tb_fbm3(vec3 p, vec3 dpdx, vec3 dpdy, float omega, int octaves)
{
    float n = tb_octaves(dpdx, dpdy, octaves);
    int ni = int(floor(n));
    float sum = 0.0, freq = 1.0, amp = 1.0;
    for (int i = 0; i < ni; i++) {
        sum += amp * tb_noise3(p * freq);
        freq *= 1.99;
        amp *= omega;
    }
    float part = n - float(ni);
    if (part > 0.0 && ni < 32)
        sum += amp * smoothstep(0.3, 0.7, part) * tb_noise3(p * freq);
    return sum;
}

// The fraction of [x0, x1] where floor(x) is odd (tb__odd_fraction). C
// differences two integrals of the square wave in double; in float that
// cancels (a box of 3e-3 cells at |x| ~ 1 lost 4e-5), so this adds up the
// odd parts instead: the partial first and last cells (k0 + 1 - x0 and
// x1 - k1 are exact or nearly) and the whole odd cells between.
bool tb_odd(float k) { return mod(abs(k), 2.0) == 1.0; }
float tb_odd_fraction(float x0, float x1)
{
    float w = x1 - x0;
    if (!(w > 1e-9 * (1.0 + abs(x0)))) {
        float m = 0.5 * (x0 + x1);
        return tb_odd(floor(m)) ? 1.0 : 0.0;
    }
    float k0 = floor(x0), k1 = floor(x1);
    if (k0 == k1)
        return tb_odd(k0) ? 1.0 : 0.0;
    float len = (tb_odd(k0) ? (k0 + 1.0) - x0 : 0.0) + (tb_odd(k1) ? x1 - k1 : 0.0);
    float whole = floor(k1 * 0.5) - floor((k0 + 1.0) * 0.5); // odd k in k0 + 1 .. k1 - 1
    return (len + whole) / w;
}

// tb_checker_box_average: the odd squares' share of [s0, s1] x [t0, t1].
float tb_checker_box_average(float s0, float s1, float t0, float t1)
{
    float fs = tb_odd_fraction(min(s0, s1), max(s0, s1)), ft = tb_odd_fraction(min(t0, t1), max(t0, t1));
    return fs + ft - 2.0 * fs * ft;
}

// tb_checker3_box_average: the odd cells' share of the box lo .. hi.
float tb_checker3_box_average(vec3 lo, vec3 hi)
{
    float ex = 1.0 - 2.0 * tb_odd_fraction(min(lo.x, hi.x), max(lo.x, hi.x));
    float ey = 1.0 - 2.0 * tb_odd_fraction(min(lo.y, hi.y), max(lo.y, hi.y));
    float ez = 1.0 - 2.0 * tb_odd_fraction(min(lo.z, hi.z), max(lo.z, hi.z));
    return 0.5 * (1.0 - ex * ey * ez);
}

#endif
