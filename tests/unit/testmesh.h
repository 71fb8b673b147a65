/* testmesh.h - small synthetic meshes for unit tests. */
#ifndef QDC_TESTMESH_H
#define QDC_TESTMESH_H

#include "qdc.h"

#include <stdint.h>

/* Deterministic pseudo-random numbers in [-1, 1]. */
static inline double tm_rand(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (double)(*s >> 11) / (double)(1ULL << 52) - 1.0;
}

/* n x n x n cubes on [0,1]^3, each split into 6 Kuhn tets, all positive. */
static inline mesh_t *tm_grid(int n, unsigned flags)
{
    static const int perm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1},
                                   {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
    int32_t nv = (n + 1) * (n + 1) * (n + 1), nt = 6 * n * n * n, t = 0;
    mesh_t *m = mesh_new(nv, nt, flags);

    if (!m)
        return NULL;
    for (int k = 0; k <= n; k++)
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                int32_t v = i + (n + 1) * (j + (n + 1) * k);
                m->xyz[3 * v] = (double)i / n;
                m->xyz[3 * v + 1] = (double)j / n;
                m->xyz[3 * v + 2] = (double)k / n;
            }
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                for (int p = 0; p < 6; p++) {
                    int c[3] = {i, j, k};
                    int32_t vs[4];
                    for (int s = 0; s < 4; s++) {
                        vs[s] = c[0] + (n + 1) * (c[1] + (n + 1) * c[2]);
                        if (s < 3)
                            c[perm[p][s]]++;
                    }
                    if (p >= 3) { /* odd permutation: swap to keep positive */
                        int32_t x = vs[1];
                        vs[1] = vs[2];
                        vs[2] = x;
                    }
                    for (int s = 0; s < 4; s++)
                        m->tets[4 * t + s] = vs[s];
                    if (m->region)
                        m->region[t] = i < n / 2 ? 1 : 2;
                    t++;
                }
    return m;
}

/* Move interior vertices randomly by up to amp (in grid units of 1/n). */
static inline void tm_perturb(mesh_t *m, int n, double amp, uint64_t seed)
{
    uint64_t s = seed ? seed : 88172645463325252ULL;
    for (int k = 1; k < n; k++)
        for (int j = 1; j < n; j++)
            for (int i = 1; i < n; i++) {
                int32_t v = i + (n + 1) * (j + (n + 1) * k);
                for (int c = 0; c < 3; c++)
                    m->xyz[3 * v + c] += amp / n * tm_rand(&s);
            }
}

#endif
