/* mesh_int.h - the internal part of mesh.h: the optimizer's connectivity
 * (incidences, 1-ring, boundary and interface faces) and helpers only lib/
 * uses. Included only inside lib/ and by the unit tests (docs/architecture.md,
 * "Public and internal headers"). Thread-safe: no global state. */
#ifndef QDC_MESH_INT_H
#define QDC_MESH_INT_H

#include "core/base_int.h"
#include "core/mesh.h"

#include <stdint.h>

/* Axis-aligned bounding box: lo[3], hi[3]; returns the diagonal length. */
double mesh_bbox(const mesh_t *m, double lo[3], double hi[3]);

/* Vertex flags in mesh_topo.vflag */
enum {
    MESH_V_BOUNDARY = 1,  /* on a face of exactly one tet */
    MESH_V_INTERFACE = 2, /* on a face between two regions */
    MESH_V_FIXED = 4,     /* locked by the user */
    MESH_V_UNUSED = 8     /* referenced by no tet */
};

/* Connectivity, built once per job (the optimizer never changes it). */
typedef struct mesh_topo {
    int32_t nv, nt;
    int32_t *tets; /* copy of the tets, each in the vertex order that is
                    * positive under the connectivity's orientation */
    int flipped;   /* 1 if any of the input's tets was flipped to get there */
    mesh_orientation orientation; /* what mesh_orient found */
    int32_t *vt_ptr; /* nv+1: incidences of vertex v are vt_idx[vt_ptr[v]..vt_ptr[v+1]) */
    int32_t *vt_idx; /* 4*nt entries, each 4*t + a (tet t, local vertex a) */
    int32_t *adj_ptr;  /* nv+1: CSR pattern of the 1-ring, diagonal included, */
    int32_t *adj_idx;  /*       columns sorted ascending */
    int32_t nbf;       /* boundary faces (faces of one tet) */
    int32_t *bfaces;   /* 3*nbf, outward for positively oriented tets */
    int32_t *bface_of; /* nbf: 4*t + f, the tet of each and the face's place in
                        * tets (opposite corner f) */
    uint8_t *oflip;    /* nt: 1 where the input's tet had two vertices swapped
                        * to be positive under the orientation (mesh_orient's
                        * flip), before tets took its canonical vertex order */
    int32_t nif;       /* interface faces (between tets of different regions) */
    int32_t *ifaces;   /* 3*nif */
    uint8_t *vflag;    /* nv MESH_V_* flags */
    int32_t nb;        /* vertices with MESH_V_BOUNDARY */
} mesh_topo;

qdc_status mesh_topo_build(const mesh_t *m, mesh_topo **out, qdc_error *err);

/* For every face 4t+f of the nt tets (f: the face opposite corner f,
 * tet_face_of), the face 4u+g of the tet u across it, or -1 on the boundary,
 * into nbr (4*nt), in parallel. QDC_EMESH for a face of 3+ tets or a
 * duplicate tet (err->index a tet; the first a serial pass meets), QDC_ENOMEM. */
qdc_status mesh_face_pairs(int32_t nv, int32_t nt, const int32_t *tets, int32_t *nbr,
                           qdc_error *err);
void mesh_topo_free(mesh_topo *t);

/* The faces of the mesh tp was built from, as the report reads them
 * (mesh_faces of mesh.h), in the caller's numbering: tets holds tp's tets in
 * their input vertex order (tp's numbering), told[t] is the caller's number
 * of tet t and vold[v] of vertex v (both NULL: the same numbering). *out is
 * the caller's (mesh_faces_free). QDC_ENOMEM. */
qdc_status mesh_faces_of_topo(const mesh_topo *tp, const int32_t *tets,
                              const int32_t *told, const int32_t *vold, mesh_faces **out);

/* Tets of topo->tets that are inverted or degenerate at coordinates xyz
 * (geom_tet_bad of core/tet.h: the count every pass compares). */
int32_t mesh_count_inverted(const mesh_topo *t, const double *xyz);

/* mesh_orient by the serial walk of docs/method.md §1 alone (mesh_orient
 * finds the same in parallel, and walks only to name the tets of a
 * connectivity that cannot be oriented): for the tests that compare them. */
qdc_status mesh_orient_walk(const mesh_t *m, uint8_t *flip, mesh_orientation *o,
                            qdc_error *err);

#endif
