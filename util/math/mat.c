#include "util/math/mat.h"

#include <math.h>
#include <string.h>

tb_mat3 tb_mat3_identity(void)
{
    return (tb_mat3){{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
}

tb_mat3 tb_mat3_mul(const tb_mat3 *a, const tb_mat3 *b)
{
    tb_mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[i][j] = a->m[i][0] * b->m[0][j] + a->m[i][1] * b->m[1][j] + a->m[i][2] * b->m[2][j];
    return r;
}

tb_mat3 tb_mat3_transpose(const tb_mat3 *a)
{
    tb_mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[i][j] = a->m[j][i];
    return r;
}

double tb_mat3_det(const tb_mat3 *a)
{
    const double(*m)[3] = a->m;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

tb_dvec3 tb_mat3_mul_vec(const tb_mat3 *a, tb_dvec3 v)
{
    const double(*m)[3] = a->m;
    return (tb_dvec3){m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                      m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                      m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

/* Infinity norm (largest absolute row sum) of an n x n matrix stored row by
 * row with row stride `stride`. +inf if an entry is infinite, NaN passes. */
static double tb__norm_inf(const double *m, int n, int stride)
{
    double best = 0.0;
    for (int i = 0; i < n; ++i) {
        double s = 0.0;
        for (int j = 0; j < n; ++j)
            s += fabs(m[i * stride + j]);
        if (!(s <= best)) /* also takes NaN */
            best = s;
    }
    return best;
}

static bool tb__all_finite(const double *m, int count)
{
    for (int i = 0; i < count; ++i)
        if (!isfinite(m[i]))
            return false;
    return true;
}

/* The common verdict of both inverses: given the matrix and its computed
 * inverse (n x n, stride `stride`), TB_OK or TB_ERR_NUMERIC. rcond is
 * 1 / (||A|| ||A^-1||), which is 1 for orthogonal matrices and does not change
 * when A is multiplied by a constant; an inverse that overflowed has an
 * infinite norm and rcond 0. */
static tb_status tb__check_rcond(const double *a, const double *inv, int n, int stride,
                                 const char *what)
{
    double na = tb__norm_inf(a, n, stride), ni = tb__norm_inf(inv, n, stride);
    double rcond = 1.0 / (na * ni);
    if (!(rcond >= TB_MAT_RCOND_MIN))
        return tb_error(TB_ERR_NUMERIC,
                        "%s is singular or ill-conditioned: reciprocal condition number "
                        "%.3g < %.3g",
                        what, isnan(rcond) ? 0.0 : rcond, TB_MAT_RCOND_MIN);
    return TB_OK;
}

tb_status tb_mat3_inverse(const tb_mat3 *a, tb_mat3 *out)
{
    if (!tb__all_finite(&a->m[0][0], 9))
        return tb_error(TB_ERR_ARG, "3x3 matrix has a non-finite entry");
    /* Work on 2^-k a, with 2^k near the largest entry: the power-of-two
     * scaling is exact and keeps the determinant (a cube) from under- or
     * overflowing for uniformly tiny or huge matrices, so the verdict
     * depends on the condition number alone. */
    double big = 0.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            big = fmax(big, fabs(a->m[i][j]));
    if (big == 0.0)
        return tb_error(TB_ERR_NUMERIC, "3x3 matrix is singular (all zero)");
    int k;
    frexp(big, &k);
    double m[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            m[i][j] = ldexp(a->m[i][j], -k);
    /* Adjugate / determinant: exact zero determinant is reported as singular;
     * anything else is judged by the condition number below. */
    tb_mat3 c;
    c.m[0][0] = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    c.m[0][1] = m[0][2] * m[2][1] - m[0][1] * m[2][2];
    c.m[0][2] = m[0][1] * m[1][2] - m[0][2] * m[1][1];
    c.m[1][0] = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    c.m[1][1] = m[0][0] * m[2][2] - m[0][2] * m[2][0];
    c.m[1][2] = m[0][2] * m[1][0] - m[0][0] * m[1][2];
    c.m[2][0] = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    c.m[2][1] = m[0][1] * m[2][0] - m[0][0] * m[2][1];
    c.m[2][2] = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    double det = m[0][0] * c.m[0][0] + m[0][1] * c.m[1][0] + m[0][2] * c.m[2][0];
    if (det == 0.0 || !isfinite(det))
        return tb_error(TB_ERR_NUMERIC, "3x3 matrix is singular (determinant %g)", det);
    double s = 1.0 / det;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            c.m[i][j] *= s;
    tb_status st = tb__check_rcond(&m[0][0], &c.m[0][0], 3, 3, "3x3 matrix");
    if (st)
        return st;
    /* a^-1 = 2^-k (2^-k a)^-1. */
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            c.m[i][j] = ldexp(c.m[i][j], -k);
    if (!tb__all_finite(&c.m[0][0], 9))
        return tb_error(TB_ERR_NUMERIC, "3x3 matrix inverse overflowed");
    *out = c;
    return TB_OK;
}

tb_mat4 tb_mat4_identity(void)
{
    return (tb_mat4){{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
}

tb_mat4 tb_mat4_from_rows(const double v[16])
{
    tb_mat4 r;
    memcpy(r.m, v, sizeof r.m);
    return r;
}

tb_mat4 tb_mat4_mul(const tb_mat4 *a, const tb_mat4 *b)
{
    tb_mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            r.m[i][j] = a->m[i][0] * b->m[0][j] + a->m[i][1] * b->m[1][j] +
                        a->m[i][2] * b->m[2][j] + a->m[i][3] * b->m[3][j];
    return r;
}

tb_mat4 tb_mat4_transpose(const tb_mat4 *a)
{
    tb_mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            r.m[i][j] = a->m[j][i];
    return r;
}

double tb_mat4_det(const tb_mat4 *a)
{
    const double(*m)[4] = a->m;
    /* 2x2 minors of the top two rows and of the bottom two rows. */
    double s0 = m[0][0] * m[1][1] - m[1][0] * m[0][1];
    double s1 = m[0][0] * m[1][2] - m[1][0] * m[0][2];
    double s2 = m[0][0] * m[1][3] - m[1][0] * m[0][3];
    double s3 = m[0][1] * m[1][2] - m[1][1] * m[0][2];
    double s4 = m[0][1] * m[1][3] - m[1][1] * m[0][3];
    double s5 = m[0][2] * m[1][3] - m[1][2] * m[0][3];
    double c5 = m[2][2] * m[3][3] - m[3][2] * m[2][3];
    double c4 = m[2][1] * m[3][3] - m[3][1] * m[2][3];
    double c3 = m[2][1] * m[3][2] - m[3][1] * m[2][2];
    double c2 = m[2][0] * m[3][3] - m[3][0] * m[2][3];
    double c1 = m[2][0] * m[3][2] - m[3][0] * m[2][2];
    double c0 = m[2][0] * m[3][1] - m[3][0] * m[2][1];
    return s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0;
}

bool tb_mat4_isfinite(const tb_mat4 *a) { return tb__all_finite(&a->m[0][0], 16); }

bool tb_mat4_is_affine(const tb_mat4 *a)
{
    return a->m[3][0] == 0.0 && a->m[3][1] == 0.0 && a->m[3][2] == 0.0 && a->m[3][3] == 1.0;
}

bool tb_mat4_equal(const tb_mat4 *a, const tb_mat4 *b)
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (a->m[i][j] != b->m[i][j])
                return false;
    return true;
}

double tb_mat4_max_abs_diff(const tb_mat4 *a, const tb_mat4 *b)
{
    double d = 0.0;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double e = fabs(a->m[i][j] - b->m[i][j]);
            if (!(e <= d))
                d = e;
        }
    return d;
}

tb_mat3 tb_mat4_linear(const tb_mat4 *a)
{
    tb_mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[i][j] = a->m[i][j];
    return r;
}

tb_mat4 tb_mat4_from_linear(const tb_mat3 *l, tb_dvec3 t)
{
    return (tb_mat4){{{l->m[0][0], l->m[0][1], l->m[0][2], t.x},
                      {l->m[1][0], l->m[1][1], l->m[1][2], t.y},
                      {l->m[2][0], l->m[2][1], l->m[2][2], t.z},
                      {0, 0, 0, 1}}};
}

tb_dvec3 tb_mat4_mul_point(const tb_mat4 *a, tb_dvec3 p)
{
    const double(*m)[4] = a->m;
    double x = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3];
    double y = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3];
    double z = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3];
    double w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
    if (w == 1.0)
        return (tb_dvec3){x, y, z};
    return (tb_dvec3){x / w, y / w, z / w};
}

tb_dvec3 tb_mat4_mul_vec(const tb_mat4 *a, tb_dvec3 v)
{
    const double(*m)[4] = a->m;
    return (tb_dvec3){m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                      m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                      m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

/* Gauss-Jordan elimination with partial pivoting on [A | I]. */
static tb_status tb__mat4_inverse_general(const tb_mat4 *a, tb_mat4 *out)
{
    double w[4][8];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            w[i][j] = a->m[i][j];
            w[i][j + 4] = (i == j) ? 1.0 : 0.0;
        }
    for (int col = 0; col < 4; ++col) {
        int piv = col;
        for (int r = col + 1; r < 4; ++r)
            if (fabs(w[r][col]) > fabs(w[piv][col]))
                piv = r;
        if (w[piv][col] == 0.0)
            return tb_error(TB_ERR_NUMERIC, "4x4 matrix is singular (zero pivot in column %d)", col);
        if (piv != col)
            for (int j = 0; j < 8; ++j) {
                double t = w[col][j];
                w[col][j] = w[piv][j];
                w[piv][j] = t;
            }
        double s = 1.0 / w[col][col];
        for (int j = 0; j < 8; ++j)
            w[col][j] *= s;
        w[col][col] = 1.0;
        for (int r = 0; r < 4; ++r) {
            if (r == col || w[r][col] == 0.0)
                continue;
            double f = w[r][col];
            for (int j = 0; j < 8; ++j)
                w[r][j] -= f * w[col][j];
            w[r][col] = 0.0;
        }
    }
    tb_mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            r.m[i][j] = w[i][j + 4];
    tb_status st = tb__check_rcond(&a->m[0][0], &r.m[0][0], 4, 4, "4x4 matrix");
    if (st)
        return st;
    if (!tb_mat4_isfinite(&r))
        return tb_error(TB_ERR_NUMERIC, "4x4 matrix inverse overflowed");
    *out = r;
    return TB_OK;
}

tb_status tb_mat4_inverse(const tb_mat4 *a, tb_mat4 *out)
{
    if (!tb_mat4_isfinite(a))
        return tb_error(TB_ERR_ARG, "4x4 matrix has a non-finite entry");
    if (!tb_mat4_is_affine(a))
        return tb__mat4_inverse_general(a, out);
    /* [L t; 0 1]^-1 = [L^-1  -L^-1 t; 0 1]. */
    tb_mat3 l = tb_mat4_linear(a), li;
    tb_status st = tb_mat3_inverse(&l, &li);
    if (st)
        return tb_error_context(st, "linear part of an affine 4x4 matrix");
    tb_dvec3 t = {a->m[0][3], a->m[1][3], a->m[2][3]};
    tb_dvec3 ti = tb_dvec3_neg(tb_mat3_mul_vec(&li, t));
    if (!tb_dvec3_isfinite(ti))
        return tb_error(TB_ERR_NUMERIC, "4x4 matrix inverse overflowed (translation)");
    *out = tb_mat4_from_linear(&li, ti);
    return TB_OK;
}

tb_mat4f tb_mat4_to_f(const tb_mat4 *a)
{
    tb_mat4f r;
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col)
            r.m[col * 4 + row] = (float)a->m[row][col];
    return r;
}
