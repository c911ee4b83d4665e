/* Internal interface of the FED module: the readers fill a mesh's input
 * arrays in place (no copy of a large file's data) and then derive the rest
 * with the same validation tb_fed_build uses. */
#ifndef TB_UTIL_MESH_FED_INTERNAL_H
#define TB_UTIL_MESH_FED_INTERNAL_H

#include "util/mesh/fed.h"

/* A mesh with the input arrays allocated (uninitialised): positions, the
 * optional arrays asked for, face_loops (nfaces + 1), loop_corners
 * (nloops + 1), corner_vert. NULL with TB_ERR_NOMEM set on failure. */
tb_fed *tb__fed_alloc(uint32_t nverts, uint32_t nfaces, uint32_t nloops, uint32_t ncorners,
                      bool normals, bool uvs, bool ids, bool materials);

/* Given the input arrays (face_loops and loop_corners as offsets, starting
 * at 0 and ending at nloops and ncorners), checks every fatal rule and
 * derives loop_face, corner_loop, edges and adjacency. On failure returns
 * TB_ERR_FORMAT with the message set and *issue filled (if not NULL); the
 * caller still owns (and frees) the mesh. */
tb_status tb__fed_finish(tb_fed *m, tb_fed_issue *issue);

#endif
