/* order.h - a spatial numbering of a mesh's vertices and tets, for memory
 * locality: vertices along a Morton (Z-order) curve through the bounding box,
 * tets by their lowest new vertex number. A mesh whose vertices come in
 * random order (points of a Delaunay tetrahedralization, say) touches memory
 * at random in every per-vertex and per-tet loop; renumbered, neighbours sit
 * next to each other. Thread-safe, no global state. */
#ifndef QDC_ORDER_H
#define QDC_ORDER_H

#include "core/mesh_int.h"

typedef struct {
    int32_t nv, nt;
    int32_t *vnew; /* nv: old vertex number -> new */
    int32_t *told; /* nt: new tet number -> old */
    int32_t *vold; /* nv: new vertex number -> old (mesh_order_take) */
    uint8_t *done; /* nt: scratch of mesh_order_give_back (mesh_order_take) */
} mesh_order;

/* The order of m (its coordinates need not be finite: a non-finite one puts
 * keys at 0, an order still valid). QDC_ENOMEM, or QDC_EINVAL for an index out
 * of range. */
qdc_status mesh_order_build(const mesh_t *m, mesh_order *o);
/* A copy of m's coordinates, tets, regions, fixed flags and triangles (not
 * their refs) in the new numbering (vertex refs and the source are not
 * copied); NULL if out of memory. */
mesh_t *mesh_order_apply(const mesh_t *m, const mesh_order *o);
/* mesh_order_apply, moving m's tets and regions instead of copying them:
 * m holds NULL in their place until mesh_order_give_back (its coordinates,
 * fixed flags, refs, triangles and source stay), so that a run on the copy
 * holds the connectivity once (20 bytes a tet). NULL if out of memory (m
 * then unchanged). */
mesh_t *mesh_order_take(mesh_t *m, mesh_order *o);
/* The tets and regions of pm (from mesh_order_take, unchanged since) back to
 * m, in m's numbering and order as they were; in place, allocating nothing,
 * so it cannot fail. pm is left without them. */
void mesh_order_give_back(mesh_order *o, mesh_t *pm, mesh_t *m);
/* Coordinates of the renumbered copy pm back into m's numbering. */
void mesh_order_restore_xyz(const mesh_order *o, const mesh_t *pm, mesh_t *m);
void mesh_order_free(mesh_order *o);

/* m renumbered in place, allocating nothing: its vertex v moves to vto[v] (a
 * permutation of 0..nv-1) in its coordinates, fixed flags, refs and point data
 * and in the vertex numbers of its tets, triangles and mid-edge nodes; its tet
 * t to tto[t] (a permutation of 0..nt-1; NULL: the order kept), with its
 * region and mid-edge nodes. The triangles keep their order and refs, a
 * vertex number out of range its value. done: scratch of max(nv, nt) bytes. */
void mesh_renumber(mesh_t *m, const int32_t *vto, const int32_t *tto, uint8_t *done);

#endif
