/* topo.h - the topology driver: the worst tets first, from a queue, each given
 * the best improving flip of its edges (edge removal) and faces (2-3 flip,
 * multi-face removal).
 * An operation is taken only when the smallest mean ratio of its cavity rises by
 * at least margin; among those of one tet, the larger gain (sum of 1 - q over the
 * old tets less over the new: the badness the cavity loses, Netgen's objective),
 * then the larger new minimum, then the smaller canonical vertex ids. The run is
 * serial and ordered by (quality, sorted vertex ids), never by address or hash,
 * so the same mesh and parameters give the same result on any thread count
 * (the flips of the tets next in the queue are evaluated ahead on every
 * thread, and each result taken only when nothing it read has changed).
 * Vertices never move and none is made: point data stays valid. */
#ifndef QDC_TOPO_H
#define QDC_TOPO_H

#include "topo/flip.h"
#include "topo/tmesh.h"

#include <stdatomic.h>

typedef struct {
    int maxring;     /* largest edge ring removed (3..FLIP_MAXRING) */
    double qgoal;    /* tets with a mean ratio below this are queued */
    double margin;   /* the cavity's smallest mean ratio must rise by this */
    double floor4;   /* no new tet with 4 constrained corners below this mean ratio */
    int rounds;      /* queue rebuilt from the whole mesh at most this many times */
    int64_t max_ops; /* operations at most (0: 4 per tet of the input) */
    int insert;      /* 1: after the flips of a round, vertex insertion (insert.h)
                      * in the tets still below qinsert, worst first */
    double qinsert;  /* tets below this mean ratio get an insertion tried */
    int split;       /* 1: before the flips, interior edge splits (split.h's
                      * split_long_edges with lsplit, qsplit and sshare) */
    double lsplit;
    double qsplit;
    double sshare;
    double imargin; /* an insertion must raise the cavity's minimum by this */
    int iangle;     /* 1: and must not lower its smallest dihedral angle */
    int contract;   /* 1: after the flips of a round, interior edge contraction
                     * (contract.h) in the tets still below qcontract */
    double qcontract;
    double cfloor;       /* > 0: contraction by gain (contract.h's qfloor, at least
                          * this and the live tets' smallest mean ratio); 0: each
                          * contraction must raise its tets' smallest */
    flip_bound bound;    /* hausd > 0 and a surface attached: boundary flips and
                          * peeling (flip.h) too; hausd 0 (default): none */
    double akeep;        /* > 0: a flip must also leave its new tets' smallest
                          * dihedral angle at least this (degrees) or at least
                          * its old tets'; 0 (default): no such condition */
    int32_t nkeep;       /* triangles (3 each) whose faces inside the mesh stay */
    const int32_t *keep; /* (tmesh_keep_tris); 0, NULL (default): none */
    int recheck;         /* 1: evaluate every queued tet and edge again, even one
                          * whose failure nothing has changed since (0, default:
                          * skipped, the same result sooner; 1 is for tests) */
} topo_params;

/* What the runs did. */
typedef struct {
    int64_t edge_removals;             /* edges removed */
    int64_t by_ring[FLIP_MAXRING + 1]; /* of which with a ring of n tets */
    int64_t flips23;                   /* 2-3 flips */
    int64_t multiface;                 /* multi-face removals */
    int64_t visits;                    /* tets taken from the queue */
    int64_t ahead;                     /* of which evaluated ahead, in parallel */
    int64_t insertions;                /* vertices inserted (insert.h, split.h) */
    int64_t splits;                    /* of which by edge splits */
    int64_t bflips;                    /* boundary edge flips */
    int64_t peels;                     /* tets peeled off the boundary */
    int64_t contractions;              /* edges contracted */
    int64_t bcontractions;             /* of which boundary edges (under a bound) */
    int32_t nv_in, nv_out;             /* vertices before and after */
    int32_t nt_in, nt_out;             /* live tets before and after */
} topo_stats;

/* The boundary triangles through a run with boundary operations. */
typedef struct {
    int32_t ntri;        /* in: triangles (3 each, 0-based), refs (may be NULL: 0), */
    const int32_t *tris; /*     of the boundary and of anything else (kept) */
    const int32_t *refs;
    int32_t ntri_out;  /* out (qdc_malloc, the caller frees): the input's triangles */
    int32_t *tris_out; /*     still there, in their order, then the new boundary */
    int32_t *refs_out; /*     triangles with the ref and orientation of theirs */
    int32_t removed;   /* input triangles no longer on the boundary */
    int32_t added;     /* new boundary triangles written (those with a ref) */
    /* The bound spent so far (may be NULL; nv entries each, the input's vertex
     * numbering), so that a run's rounds spend one bound: */
    double *vdev; /* in: each boundary face starts with the largest vdev of its
                   * corners as the distance it has moved so far (fdev);
                   * out: raised at the corners of each boundary face a boundary
                   * operation made to that face's fdev */
    uint8_t *vop; /* out: set to 1 at those corners (not cleared) */
} topo_surface;

/* maxring 10, qgoal 0.6, margin 1e-3, floor4 0.1, rounds 3, max_ops 0, insert 0,
 * qinsert 0.15, imargin 0.05, iangle 1, contract 0, qcontract 0.3, cfloor 0, split 0,
 * lsplit 1.6, qsplit 0.5, no bound, recheck 0. */
void topo_params_default(topo_params *p);

/* Improve tm in place with flips (see above). cancel (may be NULL) is polled
 * between operations: QDC_ECANCEL then, the mesh valid as it stands. st may be
 * NULL. QDC_ENOMEM. */
qdc_status topo_improve(tmesh *tm, const topo_params *p, topo_stats *st,
                        const atomic_int *cancel);

/* The whole round trip on arrays: build a tmesh from nt positive tets (4 each,
 * region and rev may be NULL; as tmesh_new), improve it, and hand back the live tets in
 * *tets_out (and their tags in *region_out when region is not NULL), allocated with
 * qdc_malloc for the caller, *nt_out their count. The vertices are not changed
 * (p->insert, p->contract and p->split are ignored). */
qdc_status topo_flip_arrays(int32_t nv, const double *xyz, int32_t nt,
                            const int32_t *tets, const int32_t *region,
                            const uint8_t *rev, const topo_params *p,
                            const atomic_int *cancel, int32_t *nt_out, int32_t **tets_out,
                            int32_t **region_out, topo_stats *st, qdc_error *err);

/* As topo_flip_arrays, with p->insert and p->contract allowed: the vertices
 * may change, so their count and coordinates come back too (*nv_out, *xyz_out,
 * allocated with qdc_malloc): the input's that are still used (or were never
 * used) in their order, unchanged, then the new ones; *vmap_out (may be NULL;
 * nv entries, qdc_malloc) the new index of each input vertex, -1 for one a
 * contraction removed.
 * sf (may be NULL) attaches the surface (tmesh_set_surface) and receives the
 * triangles after; boundary operations need it and p->bound.hausd > 0. */
qdc_status topo_full_arrays(int32_t nv, const double *xyz, int32_t nt,
                            const int32_t *tets, const int32_t *region,
                            const uint8_t *rev, const topo_params *p,
                            const atomic_int *cancel, int32_t *nv_out, double **xyz_out,
                            int32_t *nt_out, int32_t **tets_out, int32_t **region_out,
                            int32_t **vmap_out, topo_surface *sf, topo_stats *st,
                            qdc_error *err);

#endif
