/* Patches over elements: internals shared by mesh.c and patches.c. */
#ifndef TB_HOST_RADIOSITY_PATCHES_INTERNAL_H
#define TB_HOST_RADIOSITY_PATCHES_INTERNAL_H

#include "host/radiosity/radiosity.h"
#include "util/mesh/fed.h"
#include "util/mesh/mesh.h"

/* Meshes `fed` into patches (`patch_mo`; each patch's face = its FED face)
 * and then every patch into elements (`elem_mo`; each element's face = its
 * patch), conforming across patch boundaries. Both meshes are initialised
 * here and must be freed by the caller, also on error. */
tb_status tb__rad_mesh_two_level(const tb_fed *fed, const tb_mesh_opts *patch_mo, const tb_mesh_opts *elem_mo,
                                 tb_mesh *patches, tb_mesh *elems);

#endif
