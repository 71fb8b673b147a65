/* mesh.h - tetrahedral mesh data, validation and connectivity (docs/method.md §1).
 * Indices are 0-based int32. xyz holds 3 doubles per vertex, tets 4 indices per tet.
 * A tet (a,b,c,d) is positive when det[b-a, c-a, d-a] > 0 (Shewchuk's
 * orient3d(a,b,c,d) has the opposite sign).
 * Thread-safe: no global state; a mesh_t may be read by several threads. */
#ifndef QDC_MESH_H
#define QDC_MESH_H

#include "core/base.h"

#include <stdint.h>

/* Limits accepted by mesh_validate: indices are int32. */
#define MESH_MAX_VERTICES 2000000000
#define MESH_MAX_TETS 500000000

/* The file a mesh was read from, kept by io/ so that a write in the same
 * format can give that file back with only the coordinates replaced (see
 * io/meshio.h, "Spliced writing"). Opaque here: io/ extends it, and it is
 * released with the mesh through its first member. */
typedef struct mesh_source {
    void (*release)(struct mesh_source *);
} mesh_source;

/* The mesh as data: plain arrays the caller may read and write. */
typedef struct mesh {
    int32_t nv;          /* vertex count */
    int32_t nt;          /* tet count */
    double *xyz;         /* 3*nv coordinates */
    int32_t *tets;       /* 4*nt vertex indices, 0-based */
    int32_t *region;     /* nt region tags (Medit refs, physical groups), or NULL */
    uint8_t *fixed;      /* nv flags: non-zero = vertex must not move, or NULL */
    int32_t *vref;       /* nv per-vertex refs (Medit), or NULL; carried through */
    int32_t ntri;        /* surface triangles carried through unchanged (Medit */
    int32_t *tris;       /*   Triangles with their refs = boundary-condition tags): */
    int32_t *tri_ref;    /*   3*ntri indices and ntri refs (tri_ref may be NULL) */
    mesh_source *source; /* the input file (io/), or NULL; owned by the mesh */
} mesh_t;

enum { MESH_WITH_REGION = 1, MESH_WITH_FIXED = 2, MESH_WITH_VREF = 4 };

/* Allocate a mesh with zeroed arrays; the optional arrays named by flags
 * (MESH_WITH_*). Returns NULL on allocation failure or negative counts.
 * Free with mesh_free. */
mesh_t *mesh_new(int32_t nv, int32_t nt, unsigned flags);
/* Allocate m->tris (and m->tri_ref if with_ref), replacing any previous ones. */
qdc_status mesh_set_tris(mesh_t *m, int32_t ntri, int with_ref);
/* A deep copy of the arrays; the source file (m->source) is not copied. */
mesh_t *mesh_dup(const mesh_t *m);
void mesh_free(mesh_t *m);

/* What mesh_validate found that is not an error. */
typedef struct {
    int32_t n_unreferenced;     /* vertices used by no tet (kept, never moved) */
    int32_t first_unreferenced; /* -1 if none */
    int32_t n_inverted;         /* tets against the orientation of the connectivity */
    int32_t n_degenerate;       /* flat tets (core/tet.h), either sign */
    int negative_majority;      /* 1 if most tets are written negative (vertex order) */
    int32_t n_flipped;          /* tets written in the other vertex order than their
                                 * component's orientation (DOLFIN-sorted meshes: ~half) */
    int32_t n_components;       /* face-connected components */
} mesh_check;

/* The orientation found from the connectivity (mesh_orient). */
typedef struct {
    int32_t components; /* face-connected components, each oriented as a whole */
    int32_t flipped;    /* tets whose vertex order is the other one */
    int32_t inverted;   /* tets whose geometry disagrees with the orientation */
} mesh_orientation;

/* docs/method.md §1: orient the tets from the connectivity. Two tets that share a
 * face are oriented alike when they list it in opposite cyclic orders; each
 * face-connected component is walked that way and then takes, as a whole, the
 * sign most of its tets have. flip (nt bytes, caller's) receives 1 for each tet
 * whose vertex order must have two vertices swapped to be positive under that
 * orientation. A tet is inverted when its geometry disagrees with it.
 * QDC_EMESH for a connectivity that cannot be oriented (a face of 3+ tets, or a
 * component whose faces contradict each other), with err->index a tet. */
qdc_status mesh_orient(const mesh_t *m, uint8_t *flip, mesh_orientation *o,
                       qdc_error *err);
/* The same, and the flipped tets of m rewritten in the positive vertex order. */
qdc_status mesh_reorient(mesh_t *m, mesh_orientation *o, qdc_error *err);

/* Check a mesh before use. Errors (QDC_EMESH unless said): empty mesh
 * (no vertices or no tets), a coordinate that is NaN/Inf (err->index = vertex),
 * a tet index out of [0, nv) (err->index = tet), a vertex repeated inside a tet,
 * a face shared by more than two tets (non-manifold). Unreferenced vertices and
 * inverted tets are reported in *info (may be NULL), not errors. */
qdc_status mesh_validate(const mesh_t *m, mesh_check *info, qdc_error *err);

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
    int32_t *adj_ptr; /* nv+1: CSR pattern of the 1-ring, diagonal included, */
    int32_t *adj_idx; /*       columns sorted ascending */
    int32_t nbf;      /* boundary faces (faces of one tet) */
    int32_t *bfaces;  /* 3*nbf, outward for positively oriented tets */
    int32_t nif;      /* interface faces (between tets of different regions) */
    int32_t *ifaces;  /* 3*nif */
    uint8_t *vflag;   /* nv MESH_V_* flags */
    int32_t nb;       /* vertices with MESH_V_BOUNDARY */
} mesh_topo;

qdc_status mesh_topo_build(const mesh_t *m, mesh_topo **out, qdc_error *err);
void mesh_topo_free(mesh_topo *t);

/* Tets of topo->tets that are inverted or degenerate at coordinates xyz
 * (geom_tet_bad of core/tet.h: the count every pass compares). */
int32_t mesh_count_inverted(const mesh_topo *t, const double *xyz);

#endif
