/* spend.h - one Hausdorff bound for all the rounds of a --topology run
 * (topology.c; issue #31). Each round's smoothing bounds its moves from that
 * round's input and each boundary flip from the surface it finds, so without
 * a record of what the rounds before spent the bound held per round, not for
 * the run. The record: the input's coordinates and, per vertex, spent[v], a
 * bound on how far any point of a boundary or interface triangle at v lies from
 * the INPUT surface: every such triangle lies within the largest spent of its
 * corners. A vertex on no triangle a boundary operation made (op 0) has spent
 * = its distance from its input position (a triangle of the input moved by
 * its corners: each point moves by at most their largest move); one that
 * slides on a planar patch or a straight line (the shape is kept) or is a
 * corner keeps what it spent before (0 if it never moved otherwise).
 * Indices are those of the mesh the record was made for; not thread-safe
 * (one run owns it). */
#ifndef QDC_SPEND_H
#define QDC_SPEND_H

#include "core/mesh.h"
#include "opt/opt.h"

typedef struct {
    double bound;   /* the run's bound, mesh units (0: none: nothing to keep) */
    int slide;      /* boundary slide: flat vertices and corners not bounded */
    double feature; /* the feature angle, degrees (slide's classification) */
    int32_t nv;
    double *x0;    /* 3*nv: each vertex's input position */
    double *spent; /* nv, mesh units */
    uint8_t *op;   /* nv: on a triangle a boundary operation made */
    /* one round's smoothing (spend_begin .. spend_end): */
    double *xin;    /* 3*nv: the positions before it */
    double *reach;  /* nv: the largest spent over the triangles at v */
    uint8_t *kind;  /* nv: 0 not on the surface, 1 bounded, 2 not bounded */
    uint8_t *fixed; /* the mesh's own fixed flags while held ones are lent */
    int lent;       /* m->fixed is the spend's array (fixed: the mesh's) */
} spend;

/* The record of m as the run's input (x0 = m's coordinates, nothing spent),
 * for a run of o. Its bound is set later (spend_set_bound). QDC_ENOMEM. */
qdc_status spend_new(const mesh_t *m, const opt_options *o, spend *s, qdc_error *err);
void spend_free(spend *s);
/* A deep copy of a into b (b's arrays its own). QDC_ENOMEM. */
qdc_status spend_copy(spend *b, const spend *a, qdc_error *err);

/* After the run's first smoothing (which moved m's vertices within bound,
 * mesh units, of the input, as it reports): the run's bound, and what that
 * smoothing spent. QDC_ENOMEM, mesh_topo_build's. */
qdc_status spend_set_bound(spend *s, const mesh_t *m, double bound, qdc_error *err);

/* Before a round's smoothing of m: o's bound set to the largest share of the
 * budget left that most bounded vertices still have (absolute, mesh units),
 * and the vertices with less left held (m->fixed lent until spend_end). A
 * no-op when the run has no bound. QDC_ENOMEM, mesh_topo_build's. */
qdc_status spend_begin(spend *s, mesh_t *m, opt_options *o, qdc_error *err);
/* After it (whatever its outcome): m->fixed given back, spent brought up to
 * date from the moves. */
void spend_end(spend *s, mesh_t *m);

/* After a round that changed the vertices: vertex v of the record is now
 * vmap[v] (-1: gone) of nv new ones at xyz; the new ones (inside the volume)
 * have spent nothing. QDC_ENOMEM (s unchanged). */
qdc_status spend_remap(spend *s, const double *xyz, const int32_t *vmap, int32_t nv,
                       qdc_error *err);

#endif
