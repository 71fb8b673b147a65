/* mesh.h - tetrahedral mesh data, validation and orientation (docs/method.md §1);
 * public (qdc.h; the optimizer's connectivity is in mesh_int.h).
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
    int32_t *mid;        /* second-order (10-node) tets: 6*nt vertex indices, the
                          * mid-edge node of each tet's edges in the order of
                          * mesh_p2_edges; NULL for linear tets. The mid-edge
                          * nodes are vertices in no tet: the optimizer moves
                          * the corners only (opt/p2.c moves these after it) */
    struct mesh_pdata *pdata; /* the file's point-data arrays (below), or NULL */
} mesh_t;

/* Point data: arrays of values per vertex that a file carried (VTK
 * POINT_DATA, VTU <PointData>, Gmsh $NodeData), kept so that qdc's writers
 * give them back. Each holds nv*ncomp finite doubles (vertex-major: vertex
 * v's components at v*ncomp...), integers exactly as long as they are
 * within 2^53. --topology flips keeps every vertex and so every value;
 * --topology full gives kept vertices their values and a new vertex the
 * linear interpolation of the mesh before the round at its position
 * (integer arrays: the value of the nearest corner by weight). */
typedef struct {
    char *name;    /* NUL-terminated, not empty */
    int32_t ncomp; /* components per vertex, >= 1 */
    int integer;   /* 1: every value an integer (written as integers) */
    char type[16]; /* the file's value type by its VTU name ("Int32",
                    * "Float32"...; Gmsh: "double"), or "" */
    double *v;     /* nv*ncomp values */
} mesh_parray;
typedef struct mesh_pdata {
    int32_t n;       /* arrays */
    mesh_parray *a;  /* n arrays, in the file's order */
    uint8_t *made;   /* nv: 1 for a vertex whose values were interpolated
                      * (mesh_pdata_remap), or NULL when none was */
    int32_t ninterp; /* how many: the vertices made 1 */
} mesh_pdata;
/* Append an array named name[0..nlen) of ncomp components to m->pdata (made
 * if NULL): v (nv*ncomp values, from qdc_malloc*) is taken over, also on
 * failure (freed). QDC_EINVAL (m NULL, empty name, ncomp < 1, a value NaN
 * or Inf: err->index the value), QDC_ENOMEM. type may be NULL. */
qdc_status mesh_pdata_add(mesh_t *m, const char *name, size_t nlen, int32_t ncomp,
                          int integer, const char *type, double *v, qdc_error *err);
/* A deep copy of p for nv vertices; NULL if p is NULL or out of memory. */
mesh_pdata *mesh_pdata_dup(const mesh_pdata *p, int32_t nv);
/* Free p and its arrays. p may be NULL. */
void mesh_pdata_free(mesh_pdata *p);
/* m's point data for the nv vertices at xyz (3*nv) that follow a change of
 * vertices: vmap[v] (m->nv entries) the new index of m's vertex v, -1 if it
 * is gone; the new vertices (those no vmap entry names) get the linear
 * interpolation of m (its xyz, tets and values) at their position: the tet
 * of m that contains it (barycentric weights), else the nearest by the
 * weights, clamped to it; integer arrays the value of the corner with the
 * largest weight. *out is a new mesh_pdata (NULL if m has none); its
 * ninterp counts the vertices interpolated so far (m's kept ones too).
 * Builds nothing when m->pdata is NULL. QDC_ENOMEM. */
qdc_status mesh_pdata_remap(const mesh_t *m, int32_t nv, const double *xyz,
                            const int32_t *vmap, mesh_pdata **out, qdc_error *err);

/* The one edge order of a second-order tet's mid-edge nodes (VTK's
 * VTK_QUADRATIC_TETRA and Abaqus C3D10 order): edges 01, 12, 02, 03, 13, 23,
 * as the corners of each: mesh_p2_edges[e][0..1]. Readers map each file's
 * order to this one (io/; README, "Formats"). */
extern const int mesh_p2_edges[6][2];
/* Give m a zeroed mid-edge table (6*nt; the previous one freed).
 * QDC_EINVAL (m NULL), QDC_ENOMEM (m unchanged). */
qdc_status mesh_set_mid(mesh_t *m);

enum { MESH_WITH_REGION = 1, MESH_WITH_FIXED = 2, MESH_WITH_VREF = 4 };

/* A new mesh of nv vertices and nt tets, every array zeroed: xyz and tets,
 * and the optional arrays that flags name (MESH_WITH_*; the others NULL).
 * The caller fills the arrays and owns the mesh: mesh_free. Returns NULL on
 * allocation failure or a negative count. */
mesh_t *mesh_new(int32_t nv, int32_t nt, unsigned flags);
/* Give m new zeroed boundary triangles: m->tris (3*ntri) and, if with_ref,
 * m->tri_ref (ntri); the previous ones are freed, m->ntri set. m keeps owning
 * them. QDC_EINVAL (m NULL, ntri < 0) or QDC_ENOMEM (m unchanged). */
qdc_status mesh_set_tris(mesh_t *m, int32_t ntri, int with_ref);
/* A deep copy of m's arrays, owned by the caller (mesh_free); the source file
 * (m->source) is not copied. NULL if m is NULL or on allocation failure. */
mesh_t *mesh_dup(const mesh_t *m);
/* Exchange the tets of a and b: their tets, region tags, mid-edge tables and
 * tet counts (the
 * vertices, triangles and sources stay). Puts the tets of a run that changed
 * them (--topology) into a mesh that holds the rest of the input. */
void mesh_swap_tets(mesh_t *a, mesh_t *b);
/* Free m, its arrays and its source. m may be NULL. */
void mesh_free(mesh_t *m);

/* What mesh_validate found that is not an error. */
typedef struct {
    int32_t n_unreferenced;     /* vertices used by no tet, neither as a corner nor
                                 * as a mid-edge node (kept, never moved) */
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
 * component whose faces contradict each other), with err->index a tet; the
 * errors of mesh_validate's basic checks; QDC_ENOMEM. m is only read; o (not
 * NULL) receives the counts. */
qdc_status mesh_orient(const mesh_t *m, uint8_t *flip, mesh_orientation *o,
                       qdc_error *err);
/* The same, and the flipped tets of m rewritten in place in the positive
 * vertex order (m->tets changes; nothing else). o receives what was found.
 * Statuses of mesh_orient, QDC_ENOMEM. */
qdc_status mesh_reorient(mesh_t *m, mesh_orientation *o, qdc_error *err);

/* A mesh's faces as the quality report and the boundary distance read them,
 * found once and shared by the report of an input and of a result with the
 * same tets (opt_run_faces hands out the run's; report_quality_faces,
 * bderr_meshes_faces read them): each tet's orientation and the boundary. */
typedef struct {
    int32_t nt;    /* tets */
    uint8_t *flip; /* nt: mesh_orient's flip of each tet */
    int32_t ntri;  /* boundary faces (faces of one tet) */
    int32_t *tris; /* 3*ntri: each in its tet's vertex order (outward for a
                    * positive tet), ordered by their sorted vertex triples:
                    * the triangles and order of bderr_meshes */
} mesh_faces;
/* Free f and its arrays. f may be NULL. */
void mesh_faces_free(mesh_faces *f);

/* Check a mesh before use. Errors (QDC_EMESH unless said): empty mesh
 * (no vertices or no tets), a coordinate that is NaN/Inf (err->index = vertex),
 * a tet index out of [0, nv) (err->index = tet), a vertex repeated inside a tet,
 * a face shared by more than two tets (non-manifold). Unreferenced vertices and
 * inverted tets are reported in *info (may be NULL), not errors. m is only
 * read. QDC_ENOMEM too. */
qdc_status mesh_validate(const mesh_t *m, mesh_check *info, qdc_error *err);

#endif
