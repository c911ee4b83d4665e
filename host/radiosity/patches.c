/* Patches over elements (Cohen, Greenberg, Immel and Brock 1986): the
 * two-level meshing of a face and the patch bookkeeping of a radiosity mesh
 * (docs/radiosity.md, "Patches and elements"). */
#include <stdlib.h>
#include <string.h>

#include "host/radiosity/patches_internal.h"

tb_status tb__rad_mesh_two_level(const tb_fed *fed, const tb_mesh_opts *patch_mo, const tb_mesh_opts *elem_mo,
                                 tb_mesh *patches, tb_mesh *elems)
{
    tb_mesh_init(patches);
    tb_mesh_init(elems);
    tb_status st = tb_mesh_from_fed(fed, patch_mo, patches);
    if (st)
        return st;
    /* The patches as a FED (face k = patch k), with the surface's normals
     * and uvs: meshing it cuts each patch edge once for both patches that
     * share it, so the elements stay conforming across patch boundaries. */
    tb_fed *pf = NULL;
    st = tb_mesh_to_fed(patches, true, &pf);
    if (!st)
        st = tb_mesh_from_fed(pf, elem_mo, elems);
    tb_fed_free(pf);
    return st;
}

tb_status tb_rad_mesh_copy_patches(tb_rad_mesh *dst, const tb_rad_mesh *src, const uint32_t *map)
{
    free(dst->patch), free(dst->patch_poly);
    dst->patch = NULL, dst->patch_poly = NULL, dst->npatches = 0;
    if (src->npatches == 0)
        return TB_OK;
    size_t ne = dst->nelems;
    dst->patch = malloc(sizeof *dst->patch * (ne ? ne : 1));
    dst->patch_poly = malloc(sizeof *dst->patch_poly * src->npatches);
    if (!dst->patch || !dst->patch_poly) {
        free(dst->patch), free(dst->patch_poly);
        dst->patch = NULL, dst->patch_poly = NULL;
        return tb_error(TB_ERR_NOMEM, "radiosity patches: out of memory");
    }
    memcpy(dst->patch_poly, src->patch_poly, sizeof *dst->patch_poly * src->npatches);
    for (size_t i = 0; i < ne; i++)
        dst->patch[i] = src->patch[map ? map[i] : i];
    dst->npatches = src->npatches;
    return TB_OK;
}
