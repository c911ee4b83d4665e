// MIP-map lookups: the GLSL twins of texture.c's tb_mipmap_nearest,
// tb_mipmap_bilinear, tb_mipmap_trilinear and tb_mipmap_ewa (Heckbert's
// elliptical weighted average with Gaussian weights, the footprint widened by
// a unit reconstruction disc, anisotropy clamped, the two levels around the
// minor axis blended), with the repeat wrap the ray tracer uses. The C code
// accumulates in double, these in float (docs/gpu.md, "GLSL routine
// library"; tests/gpu/shading_kernels.c compares them).
//
// The includer defines `uint tb_texinfo(uint i)` and `float tb_texel(uint i)`
// (the two buffers). A texture is a record in texinfo at `rec`: channels,
// levels, width and height of level 0, then per level its width, height and
// the offset of its texels (row-major from the top row, `channels` floats
// each) in the texel buffer (the layout of shaders/shared/shade.h).
#ifndef TB_LIB_TEXTURE_GLSL
#define TB_LIB_TEXTURE_GLSL

const int TB_TEX_NEAREST = 0, TB_TEX_BILINEAR = 1, TB_TEX_TRILINEAR = 2, TB_TEX_EWA = 3;

// The repeat wrap of texel index i into 0 .. n-1 (GLSL's % is undefined for negative operands).
int tb_tex_wrap(int i, int n) { return i >= 0 ? i % n : n - 1 - (-(i + 1)) % n; }

// tb__index: the texel of coordinate s, clamped for huge or non-finite s.
int tb_tex_index(float s)
{
    if (!(s > -1e9))
        return -1000000000;
    if (s > 1e9)
        return 1000000000;
    return int(floor(s));
}

int tb_tex_channels(uint rec) { return int(tb_texinfo(rec)); }
int tb_tex_levels(uint rec) { return int(tb_texinfo(rec + 1u)); }
ivec2 tb_tex_size(uint rec, int l)
{
    uint at = rec + 4u + 3u * uint(l);
    return ivec2(tb_texinfo(at), tb_texinfo(at + 1u));
}

// Texel (x, y) of level l, wrapped.
vec4 tb_tex_fetch(uint rec, int l, int x, int y)
{
    int ch = tb_tex_channels(rec);
    uint at = rec + 4u + 3u * uint(l);
    int w = int(tb_texinfo(at)), h = int(tb_texinfo(at + 1u));
    uint b = tb_texinfo(at + 2u) + uint(tb_tex_wrap(y, h) * w + tb_tex_wrap(x, w)) * uint(ch);
    vec4 v = vec4(0.0);
    for (int c = 0; c < ch; c++)
        v[c] = tb_texel(b + uint(c));
    return v;
}

vec4 tb_tex_nearest(uint rec, float u, float v)
{
    ivec2 s = tb_tex_size(rec, 0);
    return tb_tex_fetch(rec, 0, tb_tex_index(u * float(s.x)), tb_tex_index((1.0 - v) * float(s.y)));
}

vec4 tb_tex_bilinear(uint rec, int l, float u, float v)
{
    ivec2 sz = tb_tex_size(rec, l);
    float s = u * float(sz.x) - 0.5, t = (1.0 - v) * float(sz.y) - 0.5;
    int x0 = tb_tex_index(s), y0 = tb_tex_index(t);
    float fx = s - floor(s), fy = t - floor(t);
    if (!(fx >= 0.0 && fx < 1.0))
        fx = 0.0;
    if (!(fy >= 0.0 && fy < 1.0))
        fy = 0.0;
    vec4 t00 = tb_tex_fetch(rec, l, x0, y0), t10 = tb_tex_fetch(rec, l, x0 + 1, y0);
    vec4 t01 = tb_tex_fetch(rec, l, x0, y0 + 1), t11 = tb_tex_fetch(rec, l, x0 + 1, y0 + 1);
    vec4 top = t00 + fx * (t10 - t00), bot = t01 + fx * (t11 - t01);
    return top + fy * (bot - top);
}

// A texel of level l in level-0 texels (tb__sigma).
float tb_tex_sigma(uint rec, int l)
{
    ivec2 s0 = tb_tex_size(rec, 0), sl = tb_tex_size(rec, l);
    return max(float(s0.x) / float(sl.x), float(s0.y) / float(sl.y));
}

// The fractional level whose texels are `texels` level-0 texels wide (tb__level_of).
float tb_tex_level_of(uint rec, float texels)
{
    if (!(texels > 1.0))
        return 0.0;
    int nl = tb_tex_levels(rec);
    for (int l = 0; l + 1 < nl; l++) {
        float s0 = tb_tex_sigma(rec, l), s1 = tb_tex_sigma(rec, l + 1);
        if (texels < s1) {
            if (!(s1 > s0))
                return float(l + 1);
            float f = log(texels / s0) / log(s1 / s0);
            return float(l) + max(f, 0.0);
        }
    }
    return float(nl - 1);
}

// The footprint's axes in level-0 texels (x right, y down the image).
void tb_tex_axes(uint rec, vec4 fp, out vec2 a, out vec2 b)
{
    ivec2 s = tb_tex_size(rec, 0);
    a = vec2(fp.x * float(s.x), -fp.y * float(s.y));
    b = vec2(fp.z * float(s.x), -fp.w * float(s.y));
    for (int i = 0; i < 2; i++) {
        if (isinf(a[i]) || isnan(a[i]))
            a[i] = 0.0;
        if (isinf(b[i]) || isnan(b[i]))
            b[i] = 0.0;
    }
}

vec4 tb_tex_trilinear(uint rec, float u, float v, vec4 fp)
{
    vec2 a, b;
    tb_tex_axes(rec, fp, a, b);
    float lod = tb_tex_level_of(rec, max(length(a), length(b)));
    int l0 = int(floor(lod));
    float f = lod - float(l0);
    vec4 c0 = tb_tex_bilinear(rec, l0, u, v);
    if (f > 0.0 && l0 + 1 < tb_tex_levels(rec))
        c0 += f * (tb_tex_bilinear(rec, l0 + 1, u, v) - c0);
    return c0;
}

// The EWA sum at level l for axes a0, b0 in level-0 texels; false if the
// ellipse covers more than 4096 texels (tb__ewa_level).
bool tb_tex_ewa_level(uint rec, int l, float u, float v, vec2 a0, vec2 b0, out vec4 acc)
{
    ivec2 sl = tb_tex_size(rec, l), s0 = tb_tex_size(rec, 0);
    if (sl.x == 1 && sl.y == 1) {
        acc = tb_tex_fetch(rec, l, 0, 0);
        return true;
    }
    float kx = float(sl.x) / float(s0.x), ky = float(sl.y) / float(s0.y);
    float ax = a0.x * kx, ay = a0.y * ky, bx = b0.x * kx, by = b0.y * ky;
    float m00 = ax * ax + bx * bx + 1.0, m01 = ax * ay + bx * by, m11 = ay * ay + by * by + 1.0;
    float det = m00 * m11 - m01 * m01;
    float A = m11 / det, B = -2.0 * m01 / det, C = m00 / det;
    float s = u * float(sl.x) - 0.5, t = (1.0 - v) * float(sl.y) - 0.5;
    if (!(abs(s) < 1e9 && abs(t) < 1e9))
        s = t = 0.0;
    float ex = sqrt(m00), ey = sqrt(m11);
    int x0 = int(ceil(s - ex)), x1 = int(floor(s + ex));
    int y0 = int(ceil(t - ey)), y1 = int(floor(t + ey));
    if (float(x1 - x0 + 1) * float(y1 - y0 + 1) > 4096.0)
        return false;
    vec4 sum = vec4(0.0);
    float wsum = 0.0, tail = exp(-2.0);
    for (int y = y0; y <= y1; y++) {
        float dy = float(y) - t;
        for (int x = x0; x <= x1; x++) {
            float dx = float(x) - s;
            float r2 = A * dx * dx + B * dx * dy + C * dy * dy;
            if (r2 >= 1.0)
                continue;
            float w = exp(-2.0 * r2) - tail;
            sum += w * tb_tex_fetch(rec, l, x, y);
            wsum += w;
        }
    }
    acc = wsum > 0.0 ? sum / wsum : tb_tex_bilinear(rec, l, u, v);
    return true;
}

// EWA at level l, moving up while the ellipse is too large for the level.
vec4 tb_tex_ewa_at(uint rec, int l, float u, float v, vec2 a, vec2 b)
{
    vec4 acc = vec4(0.0);
    int nl = tb_tex_levels(rec);
    for (; l < nl; l++)
        if (tb_tex_ewa_level(rec, l, u, v, a, b, acc))
            break;
    return acc;
}

vec4 tb_tex_ewa(uint rec, float u, float v, vec4 fp, float max_aniso)
{
    vec2 a, b;
    tb_tex_axes(rec, fp, a, b);
    float la = length(a), lb = length(b);
    if (la < lb) { // a: the major axis
        vec2 t2 = a;
        a = b;
        b = t2;
        float tl = la;
        la = lb;
        lb = tl;
    }
    if (la == 0.0)
        return tb_tex_bilinear(rec, 0, u, v);
    if (lb * max_aniso < la) {
        float want = la / max_aniso;
        b = lb > 0.0 ? b * (want / lb) : vec2(-a.y, a.x) * (want / la);
        lb = want;
    }
    float lod = tb_tex_level_of(rec, lb);
    int l0 = int(floor(lod));
    float f = lod - float(l0);
    vec4 acc = tb_tex_ewa_at(rec, l0, u, v, a, b);
    if (f > 0.0 && l0 + 1 < tb_tex_levels(rec))
        acc += f * (tb_tex_ewa_at(rec, l0 + 1, u, v, a, b) - acc);
    return acc;
}

// tb_mipmap_lookup with the repeat wrap and the default anisotropy limit 8.
vec4 tb_tex_lookup(uint rec, int filt, float u, float v, vec4 fp)
{
    if (filt == TB_TEX_NEAREST)
        return tb_tex_nearest(rec, u, v);
    if (filt == TB_TEX_BILINEAR)
        return tb_tex_bilinear(rec, 0, u, v);
    if (filt == TB_TEX_TRILINEAR)
        return tb_tex_trilinear(rec, u, v, fp);
    return tb_tex_ewa(rec, u, v, fp, 8.0);
}

#endif
