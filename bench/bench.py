#!/usr/bin/python3
"""qdc benchmark driver (called by bench/run.sh; see bench/README.md).

For each mesh and each tool: run the tool once under measure.py (wall, CPU,
peak RSS of that process, 600 s limit), then evaluate the output with the
evaluator tests/tools/evaluate.py against the input. Raw JSON
goes to bench/out/runs/<mesh>/, the combined rows to bench/out/results.json,
and one Markdown table to stdout and to the results file.
"""
import argparse
import datetime
import glob
import hashlib
import gzip
import json
import math
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.path.join(HERE, 'out')
PY = '/usr/bin/python3'
QDC = os.path.join(ROOT, 'build', 'rel', 'qdc')
QDC_RUN = os.path.join(OUT, 'bin', 'qdc')  # snapshot: others may rebuild QDC meanwhile
QUALITY = os.path.join(ROOT, 'tests', 'tools', 'evaluate.py')  # one evaluator for all tools
DEV = os.path.join(ROOT, 'tests', 'data', 'dev')
CORPUS = os.path.join(ROOT, 'scripts', 'corpus.py')
LIMIT = 600  # seconds, per command
NO_COND = False  # --no-cond
SAMPLES = 50000

QUICK = ['bunny_low_10k', 'bunny_tangled-low_10k', 'bracket_h0.1_noisy']
# generated meshes (scripts/corpus.py SHAPE-lowq / SHAPE-scan): (tets asked for, shape,
# classes, large?, share of the vertices on the surface). The same shape at >= 100k and
# >= 1M tets gives the quality-at-scale comparison; ball and bone are surface-heavy
# (about half the vertices on the boundary). With that share fixed the surface gets
# finer against the interior as the mesh grows (corpus.py --surface-share); the ball
# with a third of its vertices on the surface at 1.1M tets has the surface-to-interior
# spacing of the 100k ball, and tells that apart from the method's own scaling.
# The generator keeps the tets inside the shape, 80-98% of those asked for: the counts
# asked give 101k-104k and 1.00M-1.02M tets (the rows show the counts).
GEN = [('125000', 'cube', ['lowq', 'tangled'], False, 0.5),
       ('125000', 'ball', ['lowq'], False, 0.5),
       ('105000', 'bone', ['scan'], False, 0.5),
       ('1250000', 'cube', ['lowq'], True, 0.5),
       ('1260000', 'ball', ['lowq'], True, 0.5),
       ('1100000', 'ball', ['lowq'], True, 0.32),
       ('5000000', 'cube', ['lowq', 'tangled'], 'huge', 0.5)]  # ~4M tets: --huge

TOOLS = ['qdc', 'qdc-report', 'qdc-1t', 'qdc-lsq', 'qdc-fixed', 'gmsh-relocate3d',
         'gmsh-default']
PEER = 'gmsh-relocate3d'
# --topology: the peers that change connectivity (issue 31), on scripts/corpus.py's
# scanned, thin, CAD, tangled and two-region meshes; (tets asked for, corpus class, large?)
# qdc's topology modes with the boundary as its default keeps it (slide, within the
# default bound) and fixed, as the peers keep it (-nosurf, Netgen's kept faces)
TOPO_TOOLS = ['qdc', 'qdc-fixed', 'qdc-flips', 'qdc-flips-fixed', 'qdc-full',
              'qdc-full-fixed', 'mmg-optim', 'mmg-noinsert', 'netgen', 'stellar']
TOPO_GEN = [('110000', c, False) for c in ('ball-scan', 'ball-lowq', 'bone-scan', 'bone-lowq',
                                           'part-cad', 'bone-lowq-tangled', 'two-region')]
TOPO_GEN += [('1100000', c, True) for c in ('ball-scan', 'bone-lowq', 'part-cad')]
LABEL = {'input': 'input', 'qdc': 'qdc (default: slide)', 'qdc-lsq': 'qdc --boundary lsq',
         'qdc-report': 'qdc --report', 'qdc-1t': 'qdc, 1 thread',
         'qdc-fixed': 'qdc --boundary fixed',
         'gmsh-relocate3d': 'Gmsh Relocate3D', 'gmsh-default': 'Gmsh default opt',
         'qdc-flips': 'qdc --topology flips',
         'qdc-flips-fixed': 'qdc --topology flips --boundary fixed',
         'qdc-full': 'qdc --topology full',
         'qdc-full-fixed': 'qdc --topology full --boundary fixed',
         'mmg-optim': 'mmg3d -optim -nosurf', 'mmg-noinsert': 'mmg3d -optim -nosurf -noinsert',
         'netgen': 'Netgen OptimizeVolumeMesh', 'stellar': 'Stellar (boundary kept)'}
# Stellar's options for a boundary kept as the other rows keep it: no smoothing of
# boundary vertices, no 2-2 flips of boundary faces, no insertion on the boundary;
# everything else (interior smoothing, edge removal, multi-face removal, contraction,
# interior insertion) at its defaults
STELLAR_CFG = '''verbosity 1
usecolor 0
facetsmooth 0
segmentsmooth 0
fixedsmooth 0
usequadrics 0
flip22 0
insertfacet 0
insertsegment 0
minsineout 0
'''
PHASES = ['setup', 'weights', 'assembly', 'solve', 'linesearch', 'finish']
QKEYS = ['n_verts', 'n_tets', 'eta_mean', 'eta_std', 'eta_min', 'eta_p01', 'dihedral_min',
         'dihedral_max', 'n_dmin_lt_5', 'n_dmin_lt_15', 'n_dmin_lt_30', 'n_inverted',
         'n_zero_volume', 'boundary_hausdorff_rel', 'boundary_dist_mean_rel', 'same_counts',
         'same_connectivity', 'boundary_vertex_max_move', 'interior_vertices_moved',
         'n_inverted_input_order', 'n_inconsistent_faces']


def log(*a):
    print(time.strftime('%H:%M:%S'), *a, file=sys.stderr, flush=True)


def peer_path(sub, name):
    """A peer's program: $QDC_PEERS/SUB if that exists, else NAME on PATH."""
    d = os.environ.get('QDC_PEERS')
    if d and os.access(os.path.join(d, sub), os.X_OK):
        return os.path.join(d, sub)
    return shutil.which(name)


_SKIP = {}


def peer_versions(tools):
    """{peer: 'program (version)'} of the peers this run uses, with
    $QDC_PEERS for the directory (RESULTS.md names no path of this machine)."""
    out = {}
    d = os.environ.get('QDC_PEERS')
    for tool, sub, name, pat in (('mmg-optim', 'mmg/build/bin/mmg3d_O3', 'mmg3d_O3',
                                  r'MMG3D, Release [\w.]+'),
                                 ('stellar', 'stellar/Stellar', 'Stellar', r'Version [\w.]+')):
        if tool not in tools and not (tool == 'mmg-optim' and 'mmg-noinsert' in tools):
            continue
        p = peer_path(sub, name)
        if not p:
            continue
        h = subprocess.run([p, '-h'], capture_output=True, text=True, errors='replace')
        m = re.search(pat, h.stdout + h.stderr)
        shown = '$QDC_PEERS/' + sub if d and p == os.path.join(d, sub) else name
        out[name] = '%s (%s)' % (shown, m.group(0) if m else 'version ?')
    if 'netgen' in tools:
        v = subprocess.run(['dpkg-query', '-W', '-f', '${Version}', 'python3-netgen'],
                           capture_output=True, text=True).stdout.strip()
        out['Netgen'] = 'Debian python3-netgen %s' % (v or '?')
    return out


def tool_skip(tool):
    """Why TOOL cannot run here (None when it can): a peer not built or
    installed, or a qdc without --topology."""
    if tool in _SKIP:
        return _SKIP[tool]
    why = None
    if tool.startswith('mmg') and not peer_path('mmg/build/bin/mmg3d_O3', 'mmg3d_O3'):
        why = 'mmg3d_O3 not found ($QDC_PEERS/mmg/build/bin/mmg3d_O3 or PATH)'
    elif tool == 'stellar' and not peer_path('stellar/Stellar', 'Stellar'):
        why = 'Stellar not found ($QDC_PEERS/stellar/Stellar or PATH)'
    elif tool == 'netgen' and subprocess.run([PY, '-c', 'import netgen.meshing'],
                                             capture_output=True).returncode != 0:
        why = '%s cannot import netgen.meshing (apt-get install python3-netgen)' % PY
    elif tool.startswith(('qdc-flips', 'qdc-full')):
        qdc = QDC_RUN if os.path.exists(QDC_RUN) else QDC
        h = subprocess.run([qdc, 'optimize', '--help'], capture_output=True, text=True)
        if '--topology' not in h.stdout + h.stderr:
            why = 'this qdc has no --topology option (qdc optimize --help)'
    _SKIP[tool] = why
    return why


def command(tool, src, dst, base):
    if tool.startswith(('qdc-flips', 'qdc-full')):
        return ([QDC_RUN, 'optimize', src, dst, '--topology', tool.split('-')[1]] +
                (['--boundary', 'fixed'] if tool.endswith('-fixed') else []))
    if tool.startswith('mmg'):
        return ([peer_path('mmg/build/bin/mmg3d_O3', 'mmg3d_O3'), '-optim', '-nosurf'] +
                (['-noinsert'] if tool == 'mmg-noinsert' else []) + ['-in', src, '-out', dst])
    if tool == 'netgen':
        return [PY, os.path.join(HERE, 'netgen_opt.py'), src, dst, base + '.netgen.json']
    if tool == 'stellar':
        # src is the .node/.ele basename made by stellar_input; the output is
        # <basename>.1.node/.ele, turned into DST by stellar_output (not timed)
        return [peer_path('stellar/Stellar', 'Stellar'), '-s', os.path.join(OUT, 'stellar.cfg'),
                src]
    if tool.startswith('qdc'):
        # timed as a user runs it: no --report (its boundary distances and
        # second quality scan are work Gmsh does not do); the run's figures
        # come from the two summary lines on stderr (qdc_summary)
        # qdc-report: the same run with the report a service writes (timed);
        # qdc-1t: one OpenMP thread, for the speed-up of each phase
        c = [QDC_RUN, 'optimize', src, dst]
        if tool == 'qdc-1t':
            c = ['env', 'OMP_NUM_THREADS=1'] + c
        return c + {'qdc-fixed': ['--boundary', 'fixed'],
                    'qdc-lsq': ['--boundary', 'lsq'],
                    'qdc-report': ['--report', base + '.report.json']}.get(tool, [])
    method = {'gmsh-relocate3d': 'Relocate3D', 'gmsh-default': ''}[tool]
    return [PY, os.path.join(HERE, 'gmsh_opt.py'), src, dst, method, base + '.gmsh.json']


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


# ------------------------------------------------------------------ meshes --

def prepare_meshes(a):
    """Return [(name, path)] of the selected meshes, unpacking/generating them."""
    if a.topology:
        return topo_meshes(a)
    sel = []
    mdir = os.path.join(OUT, 'meshes')
    os.makedirs(mdir, exist_ok=True)
    for gz in sorted(glob.glob(os.path.join(DEV, '*.mesh.gz'))):
        name = os.path.basename(gz)[:-len('.mesh.gz')]
        if a.quick and name not in QUICK:
            continue
        dst = os.path.join(mdir, name + '.mesh')
        if not os.path.exists(dst) or os.path.getmtime(dst) < os.path.getmtime(gz):
            with gzip.open(gz, 'rb') as fi, open(dst + '.tmp', 'wb') as fo:
                shutil.copyfileobj(fi, fo)
            os.replace(dst + '.tmp', dst)
        sel.append((name, dst))
    if not a.quick:
        gdir = os.path.join(OUT, 'gen')
        for h, shape, classes, large, share in GEN:
            if (large and a.no_large) or (large == 'huge' and not a.huge):
                continue
            tag = h if share == 0.5 else '%s-share%g' % (h, share)
            gd = os.path.join(gdir, tag)
            base = shape + ('-scan' if classes == ['scan'] else '-lowq')
            want = [os.path.join(gd, base + ('' if c in ('lowq', 'scan') else '-' + c) + '.mesh')
                    for c in classes]
            if a.only and not any(re.search(a.only, '%s_%s_%s' % (shape, tag, c)) for c in classes):
                continue
            if not all(os.path.exists(w) for w in want):
                log('generating', base, 'meshes,', h, 'tets (once; reused from', gd + ')')
                subprocess.run(['timeout', str(LIMIT), PY, CORPUS, gd, '--tets', h,
                                '--only', base, '--surface-share', str(share)],
                               check=True, stdout=subprocess.DEVNULL)
            sel += [('%s_%s_%s' % (shape, tag, c), w) for c, w in zip(classes, want)]
    if a.only:
        sel = [s for s in sel if re.search(a.only, s[0])]
    return sel


def topo_meshes(a):
    """--topology: scripts/corpus.py's classes of TOPO_GEN, made once into
    bench/out/gen-topo/N (N tets asked for) and reused while the files exist."""
    sel = []
    for h, cls, large in TOPO_GEN:
        if large and not a.large:
            continue
        if a.tets and not large:
            h = str(a.tets)
        name = '%s_%s' % (cls, h)
        if a.only and not re.search(a.only, name):
            continue
        gd = os.path.join(OUT, 'gen-topo', h)
        path = os.path.join(gd, cls + '.mesh')
        if not os.path.exists(path):
            log('generating', cls, h, 'tets (once; reused from', gd + ')')
            subprocess.run(['timeout', str(4 * LIMIT), PY, CORPUS, gd, '--tets', h, '--only',
                            cls], check=True, stdout=subprocess.DEVNULL)
        sel.append((name, path))
    return sel


# --------------------------------------------------------------- evaluation --

# the evaluator and cond.py run with one BLAS thread: OpenBLAS's threads wait for each
# other by yielding, and on a loaded machine a 3-CPU-second cond.py then took over 600 s
SCORE_ENV = dict(os.environ, OPENBLAS_NUM_THREADS='1', OMP_NUM_THREADS='1')


def score_limit():
    """Time limit of the evaluator and cond.py (not timed figures)."""
    return str(max(LIMIT, 1800))


def evaluate(path, orig, dst):
    cmd = ['timeout', score_limit(), PY, QUALITY, path, '--samples', str(SAMPLES), '-o', dst]
    if orig:
        cmd[4:4] = ['--orig', orig]
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                       env=SCORE_ENV)
    if r.returncode != 0:
        log('  quality.py failed on', path, ':', r.stderr.strip()[-300:])
        return None
    return load(dst)


def renumbering(src, dst):
    """Counts equal but quality.py says the tets differ: find out whether the
    writer renumbered the vertices (Gmsh writes the nodes of the boundary
    Triangles first). Vertices that did not move are matched by position
    (within 1e-12 of the bbox diagonal, Gmsh writes ~16 digits); the moved ones
    are then found through the tets: an output tet with three matched vertices
    names an input face, whose opposite vertex (the one nearer the output
    position, when the face has two tets) is the fourth. The map is accepted
    only if it is a bijection giving exactly the input's tets."""
    from scipy.spatial import cKDTree
    quality = quality_module()
    p0, t0 = quality.compact(*quality.read_mesh(src))
    p1, t1 = quality.compact(*quality.read_mesh(dst))
    tol = 1e-12 * float(np.linalg.norm(p0.max(0) - p0.min(0)))
    d, near = cKDTree(p0).query(p1)
    m = np.where(d <= tol, near, -1)
    if not (m[m >= 0] != np.nonzero(m >= 0)[0]).any():
        return 'changed'  # the unmoved vertices kept their numbers
    opposite = {}
    for k in range(4):
        for t, face in zip(t0[:, k], np.sort(np.delete(t0, k, axis=1), axis=1)):
            opposite.setdefault(tuple(face), []).append(t)
    used = np.zeros(len(p0), bool)
    used[m[m >= 0]] = True
    guess = 0
    for _ in range(1000):
        progress = 0
        for ti in np.nonzero((m[t1] < 0).sum(axis=1) == 1)[0]:
            left = np.nonzero(m[t1[ti]] < 0)[0]
            if len(left) != 1:
                continue  # mapped meanwhile by another tet
            u = t1[ti, left[0]]
            cand = [c for c in opposite.get(tuple(sorted(m[np.delete(t1[ti], left[0])])), [])
                    if not used[c]]
            if len(cand) == 1 or (cand and guess):
                m[u] = min(cand, key=lambda c: np.linalg.norm(p0[c] - p1[u]))
                used[m[u]] = True
                progress += 1
        if not progress:
            if guess or (m >= 0).all():
                break
            guess = 1  # only ambiguous faces left: take the nearer candidate
        else:
            guess = 0
    ok = ((m >= 0).all() and len(np.unique(m)) == len(m) and
          np.array_equal(quality._tet_hash(m[t1]), quality._tet_hash(t0)))
    return 'same, renumbered' if ok else 'changed, renumbered'


def quality_module():
    sys.path.insert(0, os.path.dirname(QUALITY))
    import evaluate
    return evaluate


def gmsh_input(name, src):
    """Gmsh's Medit reader fixes the boundary only for nodes of a Triangles
    section (a mesh with Tetrahedra only puts every node in the volume and
    Relocate3D then moves boundary nodes too). Give Gmsh a copy of the mesh
    with its boundary faces appended as Triangles; vertex numbering and tets
    are unchanged, so outputs are still evaluated against the original."""
    with open(src) as f:
        text = f.read()
    if re.search(r'^\s*Triangles\b', text, re.M):
        return src
    dst = os.path.join(OUT, 'gmsh-in', name + '.mesh')
    if os.path.exists(dst) and os.path.getmtime(dst) >= os.path.getmtime(src):
        return dst
    quality = quality_module()
    pts, tets = quality.read_mesh(src)
    bf = quality.boundary_faces(tets, len(pts)) + 1
    body = re.sub(r'^\s*End\s*\Z', '', text, flags=re.M).rstrip('\n')
    os.makedirs(os.path.dirname(dst), exist_ok=True)
    with open(dst + '.tmp', 'w') as f:
        f.write(body + '\n\nTriangles\n%d\n' % len(bf))
        np.savetxt(f, np.hstack([bf, np.ones((len(bf), 1), np.int64)]), fmt='%d')
        f.write('\nEnd\n')
    os.replace(dst + '.tmp', dst)
    return dst


def write_medit(path, x, t, ref=None):
    """Medit ASCII: vertices, tets (1-based) with their refs (1 when not given)."""
    ref = np.ones(len(t), np.int64) if ref is None else ref
    with open(path + '.tmp', 'w') as f:
        f.write('MeshVersionFormatted 2\nDimension 3\nVertices\n%d\n' % len(x))
        np.savetxt(f, np.column_stack([x, np.zeros(len(x))]), fmt='%.17g %.17g %.17g %d')
        f.write('Tetrahedra\n%d\n' % len(t))
        np.savetxt(f, np.column_stack([t + 1, ref]), fmt='%d')
        f.write('End\n')
    os.replace(path + '.tmp', path)


def stellar_input(name, src):
    """SRC as Stellar reads it: BASE.node and BASE.ele (made before timing,
    like gmsh_input), the tets in Stellar's orientation (the opposite of the
    Medit files'), turned all together, never one by one, so that the inverted
    tets of a tangled mesh stay inverted. Returns BASE; Stellar writes
    BASE.1.node/.ele."""
    d = os.path.join(OUT, 'stellar-in')
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(OUT, 'stellar.cfg'), 'w') as f:
        f.write(STELLAR_CFG)
    base = os.path.join(d, name)
    for f in (base + '.1.node', base + '.1.ele'):
        if os.path.exists(f):
            os.remove(f)
    if os.path.exists(base + '.ele') and os.path.getmtime(base + '.ele') >= os.path.getmtime(src):
        return base
    quality = quality_module()
    x, t = quality.read_mesh(src)
    if quality.signed_vol6(x, t).sum() > 0:
        t = t[:, [1, 0, 2, 3]]
    with open(base + '.node', 'w') as f:
        f.write('%d 3 0 0\n' % len(x))
        np.savetxt(f, np.column_stack([np.arange(1, len(x) + 1), x]), fmt='%d %.17g %.17g %.17g')
    with open(base + '.ele', 'w') as f:
        f.write('%d 4 0\n' % len(t))
        np.savetxt(f, np.column_stack([np.arange(1, len(t) + 1), t + 1]), fmt='%d')
    return base


def read_table(path, cols):
    """Rows of a .node/.ele file (comments dropped), the first column an index."""
    with open(path) as f:
        lines = [ln.split('#', 1)[0].split() for ln in f]
    lines = [ln for ln in lines if ln]
    n = int(lines[0][0])
    return np.array([ln[:1 + cols] for ln in lines[1:1 + n]], float)


def stellar_output(inbase, dst):
    """Stellar's INBASE.1.node/.ele as Medit DST (not timed; one region)."""
    if not os.path.exists(inbase + '.1.ele'):
        return False
    nd = read_table(inbase + '.1.node', 3)
    el = read_table(inbase + '.1.ele', 4).astype(np.int64)
    pos = np.full(int(nd[:, 0].max()) + 1, -1, np.int64)
    pos[nd[:, 0].astype(np.int64)] = np.arange(len(nd))
    write_medit(dst, nd[:, 1:], pos[el[:, 1:]])
    return True


def conditioning(path, dst):
    """cond.py on PATH (the P1 Laplacian's condition number), its JSON or None
    (None too under --no-cond)."""
    if NO_COND:
        return None
    r = subprocess.run(['timeout', score_limit(), PY, os.path.join(HERE, 'cond.py'), path,
                        '-o', dst], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                       text=True, env=SCORE_ENV)
    if r.returncode != 0:
        log('  cond.py failed on', path, ': rc', r.returncode, r.stderr.strip()[-300:])
        return None
    return load(dst)


def run_case(a, name, src, tool, q_in):
    rdir = os.path.join(OUT, 'runs', name)
    os.makedirs(rdir, exist_ok=True)
    base = os.path.join(rdir, tool)
    dst = base + '.mesh'
    rowf = base + '.row.json'
    if a.resume or a.table_only:
        row = load(rowf)
        if row:
            log('  %-16s reused %s' % (tool, rowf))
            row['reused'] = True
            row.setdefault('measured', datetime.datetime.fromtimestamp(
                os.path.getmtime(rowf)).astimezone().isoformat(timespec='seconds'))
            if (a.topology and not a.table_only and row['status'] == 'ok' and
                    not row.get('cond') and os.path.exists(dst)):
                row['cond'] = conditioning(dst, base + '.cond.json')  # it failed before
                with open(rowf, 'w') as f:
                    json.dump(row, f, indent=1)
            return row
    if a.table_only and not tool_skip(tool):
        return {'mesh': name, 'tool': tool, 'status': 'not run', 'wall': 0.0, 'cpu': 0.0,
                'maxrss_mb': 0.0, 'reused': True}
    for f in (dst, base + '.gmsh.json', base + '.netgen.json', base + '.quality.json',
              base + '.cond.json'):
        if os.path.exists(f):
            os.remove(f)
    why = tool_skip(tool)
    if why:
        log('  # SKIP %s: %s' % (tool, why))
        return {'mesh': name, 'tool': tool, 'status': 'skipped', 'skip': why, 'wall': 0.0,
                'cpu': 0.0, 'maxrss_mb': 0.0}
    inp = src
    if tool.startswith('gmsh'):
        inp = gmsh_input(name, src)
    elif tool == 'stellar':
        inp = stellar_input(name, src)
    cmd = command(tool, inp, dst, base)
    runs = []
    for _ in range(max(1, a.repeat)):
        subprocess.run([PY, os.path.join(HERE, 'measure.py'), base + '.time.json',
                        str(LIMIT), '--'] + cmd, check=True)
        t = load(base + '.time.json')
        runs.append(t)
        if t['rc'] != 0 or t['timed_out']:
            break
    if tool == 'stellar' and t['rc'] == 0:
        stellar_output(inp, dst)
    # the median of the runs (wall and CPU each), the largest peak
    med = lambda k: sorted(r[k] for r in runs)[len(runs) // 2]
    row = {'mesh': name, 'tool': tool, 'cmd': ' '.join(shlex.quote(c) for c in cmd),
           'wall': med('wall'), 'cpu': med('cpu'),
           'maxrss_mb': max(r['maxrss_mb'] for r in runs), 'rc': t['rc'],
           'runs': len(runs), 'walls': [r['wall'] for r in runs],
           'measured': datetime.datetime.now().astimezone().isoformat(timespec='seconds')}
    if t['timed_out']:
        row['status'] = 'timeout'
    elif t['rc'] != 0:
        row['status'] = 'failed rc=%d' % t['rc']
    elif not os.path.exists(dst):
        row['status'] = 'no output'
    else:
        row['status'] = 'ok'
    run = qdc_summary(base + '.time.json.log') if tool.startswith('qdc') else None
    if run:
        row.update(run)
        row['opt_seconds'] = row['seconds'].get('total')
    g = load(base + '.gmsh.json')
    if g:
        row['gmsh'] = g
        row['opt_seconds'] = g['seconds']['optimize']
    g = load(base + '.netgen.json')
    if g:
        row['netgen'] = g
        row['opt_seconds'] = g['seconds']['optimize']
    if row['status'] == 'ok':
        q = evaluate(dst, src, base + '.quality.json')
        if q is None:
            row['status'] = 'evaluator failed'
        else:
            row['quality'] = {k: q.get(k) for k in QKEYS}
            if q.get('same_connectivity'):
                row['conn'] = 'same'
            elif not q.get('same_counts'):
                row['conn'] = 'changed (%+d tets)' % (q['n_tets'] - q_in['n_tets'])
            else:
                row['conn'] = renumbering(src, dst)
            row['notes'] = notes(row, q_in)
            if a.topology:
                row['cond'] = conditioning(dst, base + '.cond.json')
    if row['status'] != 'ok':
        log('  %s: %s (see %s.time.json.log)' % (tool, row['status'], base))
    if a.drop_outputs and os.path.exists(dst):
        os.remove(dst)
    with open(rowf, 'w') as f:
        json.dump(row, f, indent=1)
    return row


SUMMARY = re.compile(r'^qdc: .*: mean ratio [-\d.]+ -> ([-\d.]+), .*'
                     r'\((\S+), (\d+) iterations, (\S+), ([\d.]+)s\)\s*$', re.M)
SECONDS = re.compile(r'^qdc: seconds: (.*)$', re.M)


def qdc_summary(log_path):
    """Iterations, stop reason, solver, phase seconds and the mean ratio it
    reports, from the two summary lines qdc optimize prints on stderr."""
    try:
        with open(log_path, errors='replace') as f:
            text = f.read()
    except OSError:
        return None
    m, sec = SUMMARY.search(text), SECONDS.search(text)
    if not m or not sec:
        return None
    secs = {}
    for part in sec.group(1).split(','):
        k, _, v = part.strip().rpartition(' ')
        secs[k.replace(' ', '')] = float(v)
    secs['total'] = float(m.group(5))
    return {'iterations': int(m.group(3)), 'stop_reason': m.group(2),
            'solver': m.group(4), 'seconds': secs,
            'report_after': {'mean_ratio_mean': float(m.group(1))}}


def notes(row, q_in):
    """Flags for outputs that are worse than the input or inconsistent."""
    q, n = row['quality'], []
    if q['n_inverted'] > q_in['n_inverted']:
        n.append('more inverted than input')
    if q['eta_mean'] < q_in['eta_mean'] - 1e-9:
        n.append('mean ratio mean below input')
    if q_in['n_inverted'] == 0 and q['eta_min'] < q_in['eta_min'] - 1e-9:
        n.append('worst tet worse than input')
    if q['dihedral_min'] < q_in['dihedral_min'] - 1e-9 and q['n_inverted'] == 0:
        n.append('min dihedral below input')
    ra = row.get('report_after')
    if ra and abs(ra.get('mean_ratio_mean', q['eta_mean']) - q['eta_mean']) > 1e-3:
        n.append('report mean ratio %.4f vs evaluator %.4f' % (ra['mean_ratio_mean'],
                                                                q['eta_mean']))
    if row.get('stop_reason') not in (None, 'max-iter', 'converged', 'no-descent'):
        n.append('stop: %s' % row['stop_reason'])
    return n


# ------------------------------------------------------------------- table --

def failure(r):
    """Status of a failed row with the tool's last error line, if any."""
    msg = ''
    try:
        with open(os.path.join(OUT, 'runs', r['mesh'], r['tool'] + '.time.json.log'),
                  errors='replace') as f:
            for line in f:
                # '## Error': mmg3d; '***** ALERT': Stellar
                m = re.search(r"(\w+): Assertion (`.*') failed", line)  # C assert()
                if m and not msg:
                    msg = '%s: assertion %s failed' % m.groups()
                elif re.match(r'\s*(## |\*+ )?(Exception|Error|error|qdc:|ALERT)', line):
                    msg = line.strip()
    except OSError:
        pass
    msg = re.sub(r'^Exception:\s*', 'Gmsh: ', msg).replace('|', '/')
    msg = re.sub(r'^## Error:\s*', 'mmg3d: ', msg)
    msg = re.sub(r'^\*+ ALERT (.*?)[ *]*$', r'Stellar: \1', msg)
    return r['status'] + (' (%s)' % msg[:120] if msg else '')


def fnum(x, fmt):
    return '—' if x is None else fmt % x


def table_head(cols):
    return ['| ' + ' | '.join(cols) + ' |', '|' + '---|' * len(cols)]


def by_mesh(rows, inputs, meshes):
    """(name, input quality, rows) per evaluated mesh, in the order of MESHES."""
    for name, _ in meshes:
        if inputs.get(name) is not None:
            yield name, inputs[name], [r for r in rows if r['mesh'] == name]


def table(rows, inputs, meshes):
    out = table_head(['mesh', 'tool', 'tets', 'verts', 'iters'] + PHASES +
                     ['wall s', 'CPU s', 'RSS MB', '× R3D wall', '× R3D opt', 'η mean',
                      'η std', 'η min', 'dih min°', 'dih max°', '<5°', '<15°', '<30°', 'inv',
                      'Hausdorff rel', 'connectivity', 'notes'])
    for name, qi, mrows in by_mesh(rows, inputs, meshes):
        peer = next((r for r in mrows if r['tool'] == PEER and r['status'] == 'ok'), None)
        for r in [{'tool': 'input', 'status': 'ok', 'quality': qi}] + mrows:
            q = r.get('quality') or {}
            s = r.get('seconds') or {}
            ok = r['status'] == 'ok'
            ratio = ratio_opt = None
            if peer and ok and r['tool'] != 'input':
                ratio = r['wall'] / peer['wall']
                if r.get('opt_seconds') is not None and peer.get('opt_seconds'):
                    ratio_opt = r['opt_seconds'] / peer['opt_seconds']
            note = notes(r, qi) if r.get('quality') and timed_row(r) else []
            if not ok:
                note.insert(0, failure(r))
            cells = [name, LABEL[r['tool']], fnum(q.get('n_tets'), '%d'),
                     fnum(q.get('n_verts'), '%d'), fnum(r.get('iterations'), '%d')]
            cells += [fnum(s.get(p), '%.2f') for p in PHASES]
            timed = r['tool'] != 'input'
            cells += [fnum(r.get('wall') if timed else None, '%.2f'),
                      fnum(r.get('cpu') if timed else None, '%.2f'),
                      fnum(r.get('maxrss_mb') if timed else None, '%.0f'),
                      fnum(ratio, '%.2f'), fnum(ratio_opt, '%.2f'),
                      fnum(q.get('eta_mean'), '%.3f'), fnum(q.get('eta_std'), '%.3f'),
                      fnum(q.get('eta_min'), '%+.3f'), fnum(q.get('dihedral_min'), '%.2f'),
                      fnum(q.get('dihedral_max'), '%.2f'), fnum(q.get('n_dmin_lt_5'), '%d'),
                      fnum(q.get('n_dmin_lt_15'), '%d'), fnum(q.get('n_dmin_lt_30'), '%d'),
                      fnum(q.get('n_inverted'), '%d'),
                      fnum(q.get('boundary_hausdorff_rel'), '%.2e'),
                      r.get('conn', '—' if timed else ''), '; '.join(note)]
            out.append('| ' + ' | '.join(cells) + ' |')
    return '\n'.join(out)


def timed_row(r):
    return r['tool'] != 'input'


def summary(rows, inputs):
    """Geometric-mean speed ratio and mean-ratio gain per tool over the meshes
    where both the tool and the peer succeeded."""
    lines = ['| tool | meshes | geo-mean × R3D wall | geo-mean × R3D opt | '
             'mean Δη mean vs input | meshes with a flag |', '|---|---|---|---|---|---|']
    by = {}
    for r in rows:
        by.setdefault(r['mesh'], {})[r['tool']] = r
    for tool in TOOLS:
        w, o, d, n, flagged, failed = [], [], [], 0, 0, 0
        for m in by.values():
            r, p = m.get(tool), m.get(PEER)
            if r is None:
                continue
            if r['status'] != 'ok':
                failed += 1
                continue
            n += 1
            flagged += bool(notes(r, inputs[r['mesh']]))
            d.append(r['quality']['eta_mean'] - r['eta_in'])
            if p and p['status'] == 'ok':
                w.append(math.log(r['wall'] / p['wall']))
                if r.get('opt_seconds') and p.get('opt_seconds'):
                    o.append(math.log(r['opt_seconds'] / p['opt_seconds']))
        if n + failed == 0:
            continue
        gm = lambda v: '%.2f' % math.exp(sum(v) / len(v)) if v else '—'
        lines.append('| %s | %d%s | %s | %s | %s | %d |' % (
            LABEL[tool], n, ' (+%d not ok)' % failed if failed else '', gm(w), gm(o),
            '%+.3f' % (sum(d) / len(d)) if d else '—', flagged))
    return '\n'.join(lines) + scale_fit(rows) + speed_table(rows)


def speed_table(rows):
    """Per mesh: qdc's wall and CPU against Gmsh Relocate3D's with and without
    --report, and the speed-up from 1 to 2 threads of the whole run and of
    each phase (qdc's own phase seconds; medians of --repeat runs)."""
    by = {}
    for r in rows:
        if r['status'] == 'ok':
            by.setdefault(r['mesh'], {})[r['tool']] = r
    out = []
    for mesh, m in by.items():
        q, qr, q1, p = m.get('qdc'), m.get('qdc-report'), m.get('qdc-1t'), m.get(PEER)
        if not q or not (qr or q1 or p):
            continue
        x = lambda a, b, k: '%.2f' % (a[k] / b[k]) if a and b and b[k] else '—'
        ph = []
        for k in PHASES:
            s1 = ((q1 or {}).get('seconds') or {}).get(k)
            s2 = (q.get('seconds') or {}).get(k)
            ph.append('%.2f' % (s1 / s2) if s1 and s2 and s2 > 0.01 else '—')
        out.append('| %s | %s | %s | %s | %s | %s | %s | %s |' % (
            mesh, fnum((q.get('quality') or {}).get('n_tets'), '%d'), x(q, p, 'wall'),
            x(q, p, 'cpu'), x(qr, p, 'wall'), x(qr, p, 'cpu'), x(q1, q, 'wall'),
            ' / '.join(ph)))
    if not out:
        return ''
    return ('\n\nSpeed against Gmsh Relocate3D (same run) without and with `--report`, and '
            'from 1 to 2 threads (the 1-thread time over the 2-thread time; phases: ' +
            ', '.join(PHASES) + '):\n\n| mesh | tets | × R3D wall | × R3D CPU | --report × '
            'R3D wall | --report × R3D CPU | 1→2 threads | per phase |\n'
            '|---|---|---|---|---|---|---|---|\n' + '\n'.join(out))


def scale_fit(rows):
    """Cost of one global iteration (weights + assembly + solve + line search,
    from qdc's summary line) against the tet count: least-squares fit of
    log(seconds) = a + b log(tets) over the meshes of 10k tets and more; b = 1
    is linear. Empty when fewer than 3 meshes qualify."""
    out = []
    for tool in TOOLS:
        pts = []
        for r in rows:
            sec, it = r.get('seconds') or {}, r.get('iterations')
            nt = (r.get('quality') or {}).get('n_tets')
            if r['tool'] != tool or r['status'] != 'ok' or not it or not nt or nt < 10000:
                continue
            t = sum(sec.get(k) or 0.0 for k in ('weights', 'assembly', 'solve', 'linesearch'))
            if t > 0:
                pts.append((nt, t / it))
        if len(pts) < 3:
            continue
        xs = [math.log(n) for n, _ in pts]
        ys = [math.log(t) for _, t in pts]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        sxx = sum((x - mx) ** 2 for x in xs)
        if sxx <= 0:
            continue
        b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
        per = sorted(t / n * 1e6 for n, t in pts)
        out.append('| %s | %d | %.2f | %.2f | %d–%d |' % (
            LABEL[tool], len(pts), b, per[len(per) // 2], min(n for n, _ in pts),
            max(n for n, _ in pts)))
    if not out:
        return ''
    return ('\n\nOne global iteration against the tet count (fit of log seconds on log tets; '
            '1.00 = linear):\n\n| tool | meshes | exponent | median µs per tet per '
            'iteration | tets |\n|---|---|---|---|---|\n' + '\n'.join(out))


def topo_table(rows, inputs, meshes):
    """--topology, per row: the figures of issue 31's table and the condition
    number of the P1 Laplacian (interior vertices)."""
    out = table_head(['mesh', 'tool', 'tets', 'verts', 'η mean', 'η min', 'dih min°',
                      'dih max°', '<15°', 'inv', 'Hausdorff rel', 'CPU s', 'wall s', 'RSS MB',
                      'cond', 'notes'])
    for name, qi, mrows in by_mesh(rows, inputs, meshes):
        for r in [{'tool': 'input', 'status': 'ok', 'quality': qi,
                   'cond': qi.get('cond')}] + mrows:
            q = r.get('quality') or {}
            timed = r['tool'] != 'input' and r['status'] not in ('skipped',)
            note = notes(r, qi) if r.get('quality') and timed_row(r) else []
            if r['status'] == 'skipped':
                note = ['SKIP: ' + r['skip']]
            elif r['status'] != 'ok':
                note.insert(0, failure(r))
            if r.get('conn') and r['tool'] != 'input':
                note.append('connectivity ' + r['conn'])
            c = (r.get('cond') or {}).get('cond')
            out.append('| ' + ' | '.join([
                name, LABEL[r['tool']], fnum(q.get('n_tets'), '%d'), fnum(q.get('n_verts'), '%d'),
                fnum(q.get('eta_mean'), '%.3f'), fnum(q.get('eta_min'), '%+.3f'),
                fnum(q.get('dihedral_min'), '%.2f'), fnum(q.get('dihedral_max'), '%.1f'),
                fnum(q.get('n_dmin_lt_15'), '%d'), fnum(q.get('n_inverted'), '%d'),
                fnum(q.get('boundary_hausdorff_rel'), '%.1e'),
                fnum(r.get('cpu') if timed else None, '%.2f'),
                fnum(r.get('wall') if timed else None, '%.2f'),
                fnum(r.get('maxrss_mb') if timed else None, '%.0f'),
                fnum(c, '%.4g'), '; '.join(note)]) + ' |')
    return '\n'.join(out)


def topo_matrix(rows, inputs, meshes, tools):
    """--topology, one line per mesh: mean ratio / smallest dihedral (CPU s)
    per tool, as issue 31 tabulates them."""
    have = [t for t in tools if any(r['tool'] == t and r['status'] != 'skipped' for r in rows)]
    out = table_head(['mesh', 'input'] + [LABEL[t] for t in have])
    for name, qi, mrows in by_mesh(rows, inputs, meshes):
        cells = [name, '%.3f / %.2f°' % (qi['eta_mean'], qi['dihedral_min'])]
        for t in have:
            r = next((r for r in mrows if r['tool'] == t), None)
            if r is None or r['status'] == 'skipped':
                cells.append('—')
            elif r['status'] != 'ok' or not r.get('quality'):
                cells.append(r['status'])
            else:
                q = r['quality']
                cells.append('%.3f / %.2f° (%.1f s)%s' % (
                    q['eta_mean'], q['dihedral_min'], r['cpu'],
                    ', %d inv' % q['n_inverted'] if q['n_inverted'] else ''))
        out.append('| ' + ' | '.join(cells) + ' |')
    return '\n'.join(out)


TOPO_HEAD = '## Topology peers'


def write_topo_results(path, info, rows, inputs, meshes, tools, section, size):
    """The --topology results: a section of bench/RESULTS.md (SECTION: it
    replaces the section of the same SIZE there, the others are kept) or a
    file of its own."""
    loads = [float(x) for x in re.findall(r'load average: ([\d.]+)', info['uptime_start'] +
                                          ' ' + info['uptime_end'])]
    nrun = max((r.get('runs') or 1) for r in rows) if rows else 1
    skipped = sorted({(r['tool'], r['skip']) for r in rows if r['status'] == 'skipped'})
    when = sorted(r['measured'] for r in rows if r.get('measured'))
    title = '%s, %s tets asked for' % (TOPO_HEAD, size)
    text = [title + ' (`bench/run.sh --topology`)', '',
            '- date: %s; command: `%s`' % (info['date'], info['command']),
            '- rows measured from %s to %s' % (when[0], when[-1]) if when else
            '- no row measured',
            '- machine: %s, nproc = %d; qdc commit %s%s, binary sha256 %s…' % (
                info['cpu'], info['nproc'], info['qdc_commit'],
                ' + uncommitted changes' if info['qdc_tree_dirty'] else '',
                (info['qdc_binary_sha256'] or '?')[:12]),
            '- peers: %s' % ('; '.join('%s: `%s`' % (t, v) for t, v in
                                        info.get('peers', {}).items()) or '—'),
            '- quality: `/usr/bin/python3 %s OUT --orig IN --samples %d`; cond: '
            '`/usr/bin/python3 bench/cond.py OUT` (λmax/λmin of the P1 Laplacian stiffness '
            'matrix on the interior vertices)' % (os.path.relpath(QUALITY, ROOT), SAMPLES),
            '- `uptime` at start: `%s`; at end: `%s`' % (info['uptime_start'],
                                                       info['uptime_end']),
            '- %s' % ('one run per case' if nrun == 1 else '%d runs per case, one tool after '
                      'the other; wall and CPU are the medians' % nrun)]
    if max(loads or [0]) > 1:
        text.append('- **shared machine**: load average above 1 (other helpers\' builds and '
                    'tests on the same %d cores); wall seconds are inflated and noisy, CPU '
                    'seconds are the figure to compare' % info['nproc'])
    for t, why in skipped:
        text.append('- # SKIP %s: %s' % (t, why))
    text += ['', 'Mean ratio / smallest dihedral (CPU s):', '',
             topo_matrix(rows, inputs, meshes, tools), '', 'Per row:', '',
             topo_table(rows, inputs, meshes), '']
    text = '\n'.join(text)
    if section:
        old = open(path).read() if os.path.exists(path) else '# qdc benchmark results\n'
        parts = re.split(r'\n(?=## )', old)  # the same title replaced, in its place
        same = [i for i, p in enumerate(parts) if p.startswith(title + ' ')]
        if same:
            parts[same[0]] = text.rstrip('\n') + '\n'
        else:
            parts.append(text)
        text = '\n'.join(p.rstrip('\n') + '\n' for p in parts)
    with open(path, 'w') as f:
        f.write(text)
    return text


def kept_topo_section(path):
    """The --topology section of PATH, kept when a full run rewrites the file."""
    try:
        old = open(path).read()
    except OSError:
        return ''
    k = old.find('\n' + TOPO_HEAD)
    return '' if k < 0 else '\n' + old[k + 1:].rstrip('\n') + '\n'


def snapshot_qdc():
    """Copy build/rel/qdc so that every qdc row of this run uses one binary."""
    os.makedirs(os.path.dirname(QDC_RUN), exist_ok=True)
    shutil.copy2(QDC, QDC_RUN + '.tmp')
    os.replace(QDC_RUN + '.tmp', QDC_RUN)
    return os.path.getmtime(QDC_RUN)


def machine_info(cmdline, up0, qdc_mtime0):
    cpu = '?'
    with open('/proc/cpuinfo') as f:
        for line in f:
            if line.startswith('model name'):
                cpu = line.split(':', 1)[1].strip()
                break
    git = lambda *c: subprocess.run(['git', '-C', ROOT] + list(c), capture_output=True,
                                    text=True).stdout.strip()
    dirty = git('status', '--porcelain', '--', 'lib', 'clients', 'server', 'Makefile')
    return {'date': datetime.datetime.now().astimezone().isoformat(timespec='seconds'),
            'command': cmdline, 'nproc': os.cpu_count(), 'cpu': cpu,
            'kernel': platform.release(), 'uptime_start': up0,
            'qdc_commit': git('rev-parse', '--short', 'HEAD'),
            'qdc_tree_dirty': bool(dirty),
            'qdc_binary_mtime': datetime.datetime.fromtimestamp(
                qdc_mtime0).isoformat(timespec='seconds'),
            'qdc_binary_sha256': hashlib.sha256(open(QDC_RUN, 'rb').read()).hexdigest()
            if os.path.exists(QDC_RUN) else None}


def write_results(path, info, tab, summ, rows):
    keep = kept_topo_section(path)
    gv = next((r['gmsh']['gmsh_version'] for r in rows if r.get('gmsh')), '?')
    loads = [float(x) for x in re.findall(r'load average: ([\d.]+)', info['uptime_start'] +
                                          ' ' + info['uptime_end'])]
    shared = max(loads or [0]) > 1
    with open(path, 'w') as f:
        f.write('# qdc benchmark results\n\n')
        f.write('- date: %s\n' % info['date'])
        f.write('- command: `%s`\n' % info['command'])
        f.write('- machine: %s, nproc = %d, Linux %s\n' % (info['cpu'], info['nproc'],
                                                          info['kernel']))
        f.write('- qdc: commit %s%s, binary built %s (`build/rel/qdc` copied to '
                '`bench/out/bin/qdc` at the start, sha256 %s…), default OpenMP threads\n' % (info['qdc_commit'],
                                       ' + uncommitted changes in the working tree'
                                       if info['qdc_tree_dirty'] else '',
                                       info['qdc_binary_mtime'],
                                       (info['qdc_binary_sha256'] or '?')[:12]))
        f.write('- peers: Gmsh %s (Debian python3-gmsh), `General.NumThreads` default\n' % gv)
        f.write('- quality: `/usr/bin/python3 %s OUT --orig IN --samples %d` for every '
                'row\n' % (os.path.relpath(QUALITY, ROOT), SAMPLES))
        if info.get('table_regenerated'):
            f.write('- table regenerated from the raw JSON (nothing re-measured): %s\n'
                    % info['table_regenerated'])
        f.write('- `uptime` at start: `%s`\n- `uptime` at end: `%s`\n' % (
            info['uptime_start'], info['uptime_end']))
        if shared:
            f.write('\n**Timings were taken on a shared machine** (load average above 1: '
                    'other builds and tests were running on the same %d cores). Wall '
                    'times are noisy; compare CPU seconds and ratios within a mesh, and '
                    'do not read small differences.\n' % info['nproc'])
        nrun = max((r.get('runs') or 1) for r in rows) if rows else 1
        f.write('\nColumns are explained in [README.md](README.md). %s; raw JSON in '
                '`bench/out/runs/` (not committed).\n\n' % (
                    'One run per case' if nrun == 1 else
                    '%d runs per case, one tool after the other; wall and CPU are the '
                    'medians' % nrun))
        f.write('## Summary\n\n' + summ + '\n\n## Per mesh\n\n' + tab + '\n' + keep)


def main():
    global LIMIT, SAMPLES, NO_COND
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument('--quick', action='store_true',
                    help='3 small dev meshes, no generated meshes, no Gmsh default optimizer')
    ap.add_argument('--no-large', action='store_true', help='skip the ~1M-tet mesh')
    ap.add_argument('--huge', action='store_true',
                    help='also the ~4M-tet cubes (low quality and tangled)')
    ap.add_argument('--only', metavar='REGEX', help='only meshes whose name matches')
    ap.add_argument('--repeat', type=int, default=1, metavar='N',
                    help='run each case N times; wall and CPU are the medians')
    ap.add_argument('--tools', nargs='+', choices=TOOLS + TOPO_TOOLS[2:],
                    help='subset of tools')
    ap.add_argument('--topology', action='store_true',
                    help='the topology peers (mmg3d, Netgen, Stellar, qdc --topology) on '
                         'scanned, thin, CAD, tangled and two-region ~100k-tet meshes, with '
                         'the P1 Laplacian condition number; writes the "Topology peers" '
                         'section of bench/RESULTS.md')
    ap.add_argument('--large', action='store_true',
                    help='with --topology: also the ~1M-tet meshes')
    ap.add_argument('--tets', type=int, metavar='N',
                    help='with --topology: the tets asked of scripts/corpus.py for the '
                         'smaller meshes (default %s; e.g. 5000 to try the bench quickly)'
                         % TOPO_GEN[0][0])
    ap.add_argument('--samples', type=int, default=SAMPLES, metavar='N',
                    help="the evaluator's boundary samples per surface (default %d)" % SAMPLES)
    ap.add_argument('--limit', type=float, default=LIMIT, metavar='SECONDS',
                    help='time limit per command (default %d)' % LIMIT)
    ap.add_argument('--resume', action='store_true',
                    help='reuse finished cases from bench/out/runs (split a long run)')
    ap.add_argument('--table-only', action='store_true',
                    help='write the table from the finished cases in bench/out/runs, run '
                         'nothing (the cases not finished show as "not run")')
    ap.add_argument('--no-cond', action='store_true',
                    help='with --topology: no condition numbers (bench/cond.py; its '
                    'eigenvalue solves cost more than some runs on a busy machine)')
    ap.add_argument('--drop-outputs', action='store_true',
                    help='delete optimized meshes after evaluation (saves disk)')
    ap.add_argument('--results', metavar='FILE',
                    help='where to write the Markdown results (default: bench/RESULTS.md '
                         'for a full run, bench/out/RESULTS.md otherwise)')
    ap.add_argument('--cmdline', default=None, help=argparse.SUPPRESS)
    a = ap.parse_args()
    NO_COND = a.no_cond
    up0 = subprocess.run(['uptime'], capture_output=True, text=True).stdout.strip()
    LIMIT, SAMPLES = a.limit, a.samples
    tools = a.tools or (TOPO_TOOLS if a.topology else
                        [t for t in TOOLS if not (a.quick and t == 'gmsh-default')])
    if 'qdc' in ''.join(tools) and not os.access(QDC, os.X_OK):
        sys.exit('bench: %s missing; run `make all`' % QDC)
    if a.resume and os.path.exists(QDC_RUN):
        qdc_mtime0 = os.path.getmtime(QDC_RUN)  # keep the binary the reused rows came from
    else:
        qdc_mtime0 = snapshot_qdc() if os.path.exists(QDC) else 0
    info = machine_info(a.cmdline or ' '.join(sys.argv), up0, qdc_mtime0)
    if a.topology:
        info['peers'] = peer_versions(tools)
    meshes = prepare_meshes(a)
    if not meshes:
        sys.exit('bench: no mesh selected')
    rows, inputs = [], {}
    n = len(meshes)
    for i, (name, src) in enumerate(meshes, 1):
        log('[%d/%d] %s' % (i, n, name))
        os.makedirs(os.path.join(OUT, 'runs', name), exist_ok=True)
        qf = os.path.join(OUT, 'runs', name, 'input.quality.json')
        q_in = load(qf) if a.resume or a.table_only else None
        q_in = q_in or (None if a.table_only else evaluate(src, None, qf))
        if q_in is None:
            continue
        if a.topology:
            cf = os.path.join(OUT, 'runs', name, 'input.cond.json')
            c = load(cf) if a.resume or a.table_only else None
            q_in['cond'] = c or (None if a.table_only else conditioning(src, cf))
        inputs[name] = q_in
        for tool in tools:
            row = run_case(a, name, src, tool, q_in)
            row['eta_in'] = q_in['eta_mean']
            rows.append(row)
            q = row.get('quality') or {}
            log('  %-16s %-8s wall %7.2fs cpu %7.2fs rss %6.0fMB  eta %.3f -> %s  dmin %s' % (
                tool, row['status'], row['wall'], row['cpu'], row['maxrss_mb'],
                q_in['eta_mean'], fnum(q.get('eta_mean'), '%.3f'),
                fnum(q.get('dihedral_min'), '%.2f')))
    info['uptime_end'] = subprocess.run(['uptime'], capture_output=True,
                                        text=True).stdout.strip()
    rjson = os.path.join(OUT, 'results-topology.json' if a.topology else 'results.json')
    old = load(rjson)
    if (rows and all(r.get('reused') for r in rows) and old and
            {(r['mesh'], r['tool']) for r in old['rows']} == {(r['mesh'], r['tool']) for r in rows}):
        # nothing was measured now: keep the measuring run's date, command and load
        info = dict(old['info'], table_regenerated='%s by `%s`' % (info['date'], info['command']))
    for r in rows:
        r.pop('reused', None)
    with open(rjson, 'w') as f:
        json.dump({'info': info, 'inputs': inputs, 'rows': rows}, f, indent=1)
    full = not (a.quick or a.only or a.tools or a.tets)
    if a.topology:
        path = a.results or (os.path.join(HERE, 'RESULTS.md') if full
                             else os.path.join(OUT, 'RESULTS-topology.md'))
        text = write_topo_results(path, info, rows, inputs, meshes, tools,
                                  section=os.path.basename(path) == 'RESULTS.md',
                                  size=str(a.tets or TOPO_GEN[0][0]) +
                                  (' and %s' % TOPO_GEN[-1][0] if a.large else ''))
        log('wrote', path, 'and', rjson)
        print(text[text.find(TOPO_HEAD):])
        return
    tab, summ = table(rows, inputs, meshes), summary(rows, inputs)
    path = a.results or (os.path.join(HERE, 'RESULTS.md') if full
                         else os.path.join(OUT, 'RESULTS.md'))
    write_results(path, info, tab, summ, rows)
    log('wrote', path, 'and', rjson)
    print(tab)


if __name__ == '__main__':
    main()
