// qdcd web console: plain modern JS, no build step, no libraries. Everything
// here goes through the public HTTP API (proto/openapi.yaml), so whatever the
// page does a script can do too.
'use strict';

// ------------------------------------------------------------------ helpers --

const $ = (id) => document.getElementById(id);

function el(tag, attrs, ...kids) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
        if (v === undefined || v === null || v === false) continue;
        if (k === 'class') e.className = v;
        else if (k === 'text') e.textContent = v;
        else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
        else if (k in e && typeof v !== 'string') e[k] = v;
        else e.setAttribute(k, v === true ? '' : v);
    }
    for (const kid of kids) if (kid !== null && kid !== undefined) e.append(kid);
    return e;
}

const fix = (x, d) => (typeof x === 'number' && isFinite(x) ? x.toFixed(d) : '–');
const sgn = (x, d) => (typeof x === 'number' && isFinite(x) ? (x >= 0 ? '+' : '') + x.toFixed(d) : '–');
const int = (x) => (typeof x === 'number' ? x.toLocaleString('en-US') : '–');

function bytes(n) {
    if (typeof n !== 'number') return '–';
    if (n < 1024) return n + ' B';
    if (n < 1048576) return (n / 1024).toFixed(1) + ' KiB';
    return (n / 1048576).toFixed(1) + ' MiB';
}

function dur(s) {
    if (typeof s !== 'number' || !isFinite(s) || s < 0) return '–';
    if (s < 10) return s.toFixed(2) + ' s';
    if (s < 120) return s.toFixed(1) + ' s';
    if (s < 7200) return Math.floor(s / 60) + ' min ' + Math.round(s % 60) + ' s';
    return (s / 3600).toFixed(1) + ' h';
}

function when(t) {
    if (!t) return '–';
    const d = new Date(t * 1000);
    const now = new Date();
    const hm = d.toLocaleTimeString([], { hour: '2-digit', minute: '2-digit', second: '2-digit' });
    return d.toDateString() === now.toDateString() ? hm : d.toLocaleDateString() + ' ' + hm;
}

function elapsed(j) {
    const now = Date.now() / 1000;
    if (j.state === 'queued') return 'waiting ' + dur(now - j.created);
    if (!j.started) return '–';
    return dur((j.finished || now) - j.started);
}

const short = (id) => id.slice(0, 8);

// --------------------------------------------------------------- API access --
// With --tokens the daemon answers 401: ask for a token once, keep it in this
// tab's sessionStorage (never localStorage, never a cookie), retry.

const TOKEN_KEY = 'qdc.token';
let tokenWaiters = null;

function token() {
    return sessionStorage.getItem(TOKEN_KEY) || '';
}

function authHeaders(h) {
    const t = token();
    const out = Object.assign({}, h || {});
    if (t) out.Authorization = 'Bearer ' + t;
    return out;
}

function askToken(message) {
    if (!tokenWaiters) {
        tokenWaiters = [];
        const d = $('token-dialog');
        $('token-error').hidden = !message;
        $('token-error').textContent = message || '';
        $('token-input').value = '';
        if (!d.open) d.showModal();
        $('token-input').focus();
    }
    return new Promise((resolve) => tokenWaiters.push(resolve));
}

function tokenEntered(ev) {
    ev.preventDefault();
    const t = $('token-input').value.trim();
    if (!t) return;
    sessionStorage.setItem(TOKEN_KEY, t);
    $('token-dialog').close();
    $('forget').hidden = false;
    const w = tokenWaiters || [];
    tokenWaiters = null;
    w.forEach((resolve) => resolve());
}

// fetch() with the token; a 401 asks for one and retries.
async function api(path, opts) {
    opts = opts || {};
    for (let tries = 0; ; tries++) {
        const res = await fetch(path, Object.assign({}, opts, { headers: authHeaders(opts.headers) }));
        if (res.status !== 401) {
            setConn(true);
            return res;
        }
        const had = token();
        sessionStorage.removeItem(TOKEN_KEY);
        await askToken(had ? 'That token was refused.' : '');
    }
}

async function apiJSON(path, opts) {
    const res = await api(path, opts);
    const body = await res.json().catch(() => null);
    if (!res.ok) throw problem(res.status, body);
    return body;
}

function problem(status, body) {
    const e = new Error(body && (body.detail || body.title) ? (body.title + ': ' + body.detail) : 'HTTP ' + status);
    e.status = status;
    e.body = body;
    return e;
}

function describeProblem(status, b) {
    if (!b) return 'HTTP ' + status;
    let s = (b.title || 'error') + ' (' + status + ')' + (b.detail ? ': ' + b.detail : '');
    const where = ['line', 'column', 'offset', 'index', 'kind', 'parameter', 'max_bytes']
        .filter((k) => b[k] !== undefined).map((k) => k + ' ' + b[k]);
    if (where.length) s += '\n' + where.join(', ');
    return s;
}

let connOk = null;
function setConn(ok) {
    if (ok === connOk) return;
    connOk = ok;
    $('conn').textContent = ok ? '' : 'qdcd is not answering…';
}

// ------------------------------------------------------------------- router --

let view = null; // {name, id, stop()}

function route() {
    if (view && view.stop) view.stop();
    const m = location.pathname.match(/^\/ui\/jobs\/([0-9a-f]{32})$/);
    if (m) {
        $('view-list').hidden = true;
        $('view-job').hidden = false;
        view = jobView(m[1]);
    } else {
        $('view-job').hidden = true;
        $('view-list').hidden = false;
        view = listView();
    }
}

function go(path) {
    if (path !== location.pathname) history.pushState(null, '', path);
    route();
    window.scrollTo(0, 0);
}

document.addEventListener('click', (ev) => {
    const a = ev.target.closest('a[data-nav]');
    if (!a || ev.ctrlKey || ev.metaKey || ev.shiftKey || ev.button !== 0) return;
    ev.preventDefault();
    go(a.getAttribute('href'));
});
window.addEventListener('popstate', route);

// ---------------------------------------------------------------- job list --

// The options the form offers: their types, valid values, defaults and help
// come from GET /v1/options (the library's table, as `qdc options` prints it),
// so a new default shows here without touching the page.
const MAIN_OPTIONS = ['metric', 'boundary', 'hausd', 'topology', 'max_iter', 'stall', 'mode', 'time_limit',
    'finish', 'angle_polish', 'tetgen_quality'];
let OPTIONS = []; // the table's entries named in MAIN_OPTIONS, in that order

const MESH_EXT = { mesh: 'medit', qmesh: 'qmesh', json: 'json', msh: 'gmsh', vtk: 'vtk', vtu: 'vtu' };
const SURF_EXT = { stl: 'stl', obj: 'obj', off: 'off', poly: 'poly', smesh: 'smesh' };

const listState = { filter: '', jobs: [], first: new Map(), firstBusy: new Set() };
let chosen = null; // {file, name, format, surface, gz}

// The short help shown under a name: the table's text up to its first
// parenthesis, and up to a colon when still long (the whole text is the tooltip).
function shortHelp(h) {
    const s = h.split(' (')[0];
    return s.length > 60 ? s.split(': ')[0] : s;
}

let optionsLoading = null;
function buildOptions() {
    const box = $('opts');
    if (box.childElementCount || optionsLoading) return;
    optionsLoading = apiJSON('/v1/options').then((b) => {
        OPTIONS = MAIN_OPTIONS.map((n) => b.options.find((o) => o.name === n)).filter(Boolean);
        for (const o of OPTIONS) {
            let input;
            if (o.type === 'word') {
                input = el('select', { name: o.name }, ...o.values.map((v) => el('option', { value: v, text: v })));
                input.value = o.default;
            } else if (o.type === 'bool') {
                input = el('input', { type: 'checkbox', name: o.name });
                input.checked = o.default === 'on';
            } else {
                input = el('input', { type: o.type === 'hausd' ? 'text' : 'number', name: o.name, value: o.default,
                    min: o.min !== undefined ? String(o.min) : null, max: o.max !== undefined && o.max < 1e100 ? String(o.max) : null,
                    step: o.type === 'integer' ? '1' : 'any' });
            }
            input.dataset.default = o.default;
            const title = o.help + ' (valid: ' + o.valid + ')';
            const def = el('span', { class: 'def', text: 'default ' + o.default + ' · ' + shortHelp(o.help) });
            const label = o.type === 'bool'
                ? el('label', { class: 'check', title }, input, el('span', {}, o.name + ' ', def))
                : el('label', { title }, el('span', {}, o.name + ' ', def), input);
            if (o.surface) label.dataset.surface = '1';
            box.append(label);
        }
        surfaceOptions(chosen ? chosen.surface : false);
    }).catch((e) => {
        $('submit-error').textContent = 'The option table (GET /v1/options) did not load: ' + (e.message || e);
        $('submit-error').hidden = false;
    }).finally(() => { optionsLoading = null; });
}

function surfaceOptions(on) {
    for (const l of $('opts').querySelectorAll('label[data-surface]')) {
        l.classList.toggle('disabled', !on);
        l.querySelector('input').disabled = !on;
    }
}

function chooseFile(file) {
    $('submit-error').hidden = true;
    if (!file) return;
    let name = file.name.toLowerCase();
    const gz = name.endsWith('.gz');
    if (gz) name = name.slice(0, -3);
    const ext = name.includes('.') ? name.slice(name.lastIndexOf('.') + 1) : '';
    const surface = ext in SURF_EXT;
    chosen = { file, format: MESH_EXT[ext] || SURF_EXT[ext] || '', surface, gz };
    $('file-info').textContent = file.name + ' · ' + bytes(file.size) + ' · ' +
        (chosen.format ? (surface ? 'surface (' + chosen.format + '), tetrahedralized by TetGen first' : chosen.format)
            : 'format sniffed by qdcd') + (gz ? ' · gunzipped here before upload' : '');
    surfaceOptions(surface);
    $('submit-btn').disabled = false;
}

function optionQuery() {
    const q = new URLSearchParams();
    if (chosen.format) q.set('format', chosen.format);
    for (const o of OPTIONS) {
        const input = $('opts').querySelector('[name="' + o.name + '"]');
        if (o.surface && !chosen.surface) continue;
        const v = o.type === 'bool' ? (input.checked ? 'on' : 'off') : input.value.trim();
        if (v !== '' && v !== o.default) q.set(o.name, v);
    }
    return q.toString();
}

async function submit(ev) {
    ev.preventDefault();
    if (!chosen) return;
    const btn = $('submit-btn');
    const bar = $('upload-progress');
    const status = $('upload-status');
    const err = $('submit-error');
    btn.disabled = true;
    err.hidden = true;
    let body = chosen.file;
    try {
        if (chosen.gz) {
            status.textContent = 'decompressing…';
            body = await new Response(chosen.file.stream().pipeThrough(new DecompressionStream('gzip'))).blob();
        }
    } catch (e) {
        err.textContent = 'cannot gunzip ' + chosen.file.name + ': ' + e.message;
        err.hidden = false;
        btn.disabled = false;
        status.textContent = '';
        return;
    }
    const url = '/v1/jobs' + (optionQuery() ? '?' + optionQuery() : '');
    for (;;) {
        const r = await upload(url, body, bar, status);
        if (r.status === 401) {
            sessionStorage.removeItem(TOKEN_KEY);
            await askToken(r.hadToken ? 'That token was refused.' : '');
            continue;
        }
        bar.hidden = true;
        btn.disabled = false;
        if (r.status === 202 && r.body && r.body.id) {
            status.textContent = '';
            go('/ui/jobs/' + r.body.id);
        } else {
            status.textContent = '';
            err.textContent = r.status ? describeProblem(r.status, r.body) : 'upload failed: qdcd did not answer';
            err.hidden = false;
        }
        return;
    }
}

// XMLHttpRequest, for its upload progress events (fetch has none).
function upload(url, body, bar, status) {
    return new Promise((resolve) => {
        const xhr = new XMLHttpRequest();
        const hadToken = !!token();
        xhr.open('POST', url);
        const h = authHeaders({ 'Content-Type': 'application/octet-stream' });
        for (const [k, v] of Object.entries(h)) xhr.setRequestHeader(k, v);
        bar.hidden = false;
        bar.value = 0;
        xhr.upload.onprogress = (e) => {
            if (e.lengthComputable) {
                bar.value = e.loaded / e.total;
                status.textContent = 'uploading ' + bytes(e.loaded) + ' of ' + bytes(e.total);
            }
        };
        xhr.upload.onload = () => { status.textContent = 'checking the mesh…'; };
        xhr.onload = () => {
            let b = null;
            try { b = JSON.parse(xhr.responseText); } catch (e) { /* not JSON */ }
            resolve({ status: xhr.status, body: b, hadToken });
        };
        xhr.onerror = () => resolve({ status: 0, body: null, hadToken });
        xhr.send(body);
    });
}

async function listJobs() {
    const all = [];
    let page = '';
    for (let i = 0; i < 20; i++) {
        const b = await apiJSON('/v1/jobs?page_size=1000' + (page ? '&page_token=' + encodeURIComponent(page) : ''));
        all.push(...b.jobs);
        if (!b.next_page_token) break;
        page = b.next_page_token;
    }
    return all.reverse(); // newest first
}

// The input's quality is record 0 of a job's progress (fetched once per job).
function firstRecord(j) {
    const s = listState;
    if (s.first.has(j.id) || s.firstBusy.has(j.id) || !(j.iterations > 0)) return;
    s.firstBusy.add(j.id);
    apiJSON('/v1/jobs/' + j.id + '/progress?after=-1')
        .then((b) => { if (b.records.length) s.first.set(j.id, b.records[0]); })
        .catch(() => {})
        .finally(() => { s.firstBusy.delete(j.id); if (view && view.name === 'list') renderJobs(); });
}

async function jobAction(id, what) {
    try {
        if (what === 'cancel') await apiJSON('/v1/jobs/' + id + ':cancel', { method: 'POST' });
        else {
            const res = await api('/v1/jobs/' + id, { method: 'DELETE' });
            if (!res.ok && res.status !== 404) throw problem(res.status, await res.json().catch(() => null));
        }
    } catch (e) {
        alertError(e);
    }
}

function alertError(e) {
    const box = $('view-job').hidden ? $('submit-error') : $('job-error');
    box.textContent = e.body ? describeProblem(e.status, e.body) : String(e.message || e);
    box.hidden = false;
}

function renderJobs() {
    const s = listState;
    const tbody = $('jobs').tBodies[0];
    const rows = s.jobs.filter((j) => !s.filter || j.state === s.filter);
    const frag = document.createDocumentFragment();
    for (const j of rows) {
        firstRecord(j);
        const f = s.first.get(j.id);
        const p = j.progress;
        const acts = el('td', { class: 'actions' });
        if (!j.done)
            acts.append(el('button', { type: 'button', class: 'small', text: 'Cancel', 'data-act': 'cancel',
                onclick: () => jobAction(j.id, 'cancel').then(refreshList) }));
        acts.append(el('button', { type: 'button', class: 'small danger', text: 'Delete', 'data-act': 'delete',
            onclick: () => jobAction(j.id, 'delete').then(refreshList) }));
        const tets = j.mesh.tets || (j.mesh.surface ? 'surface' : 0);
        frag.append(el('tr', { 'data-id': j.id, 'data-state': j.state },
            el('td', {}, el('a', { href: '/ui/jobs/' + j.id, 'data-nav': true, class: 'id', text: short(j.id) })),
            el('td', {}, el('span', { class: 'state ' + j.state, text: j.state + (j.cancel_requested && !j.done ? ' (cancelling)' : '') })),
            el('td', { class: 'num', text: typeof tets === 'number' ? int(tets) : tets }),
            el('td', { class: 'num opt', text: int(j.mesh.vertices) }),
            el('td', { class: 'opt', text: j.mesh.format + ' · ' + bytes(j.mesh.bytes) }),
            el('td', { class: 'num', text: (f ? fix(f.mean_ratio_mean, 4) : '–') + ' → ' + (p ? fix(p.mean_ratio_mean, 4) : '–') }),
            el('td', { class: 'num opt', text: (f ? fix(f.dihedral_min, 1) + '°' : '–') + ' → ' + (p ? fix(p.dihedral_min, 1) + '°' : '–') }),
            el('td', { class: 'num', text: elapsed(j) }),
            el('td', { class: 'opt', text: when(j.created) }),
            acts));
    }
    tbody.replaceChildren(frag);
    $('jobs-empty').hidden = rows.length > 0;
    $('jobs-empty').textContent = s.jobs.length ? 'No ' + s.filter + ' jobs.' : 'No jobs yet: submit a mesh above.';
}

let refreshList = async () => {};

function listView() {
    let timer = 0;
    let stopped = false;
    buildOptions();
    document.title = 'qdcd · jobs';
    refreshList = async () => {
        try {
            listState.jobs = await listJobs();
            if (!stopped) renderJobs();
        } catch (e) {
            if (e instanceof TypeError) setConn(false);
        }
    };
    const tick = async () => {
        if (stopped) return;
        buildOptions(); // again if the table did not load the first time
        if (!document.hidden) await refreshList();
        if (!stopped) timer = setTimeout(tick, 1500);
    };
    tick();
    return { name: 'list', stop: () => { stopped = true; clearTimeout(timer); } };
}

// ----------------------------------------------------------------- job view --

const FORMATS = [
    ['qmesh', 'qmesh', 'QMESH (binary)'], ['medit', 'mesh', 'Medit'], ['json', 'json', 'JSON'],
    ['gmsh', 'msh', 'Gmsh 4.1'], ['gmsh-bin', 'msh', 'Gmsh 4.1 binary'], ['gmsh22', 'msh', 'Gmsh 2.2'],
    ['vtk', 'vtk', 'VTK legacy'], ['vtk-ascii', 'vtk', 'VTK legacy ASCII'], ['vtu', 'vtu', 'VTU'],
    ['vtu-ascii', 'vtu', 'VTU ASCII'], ['gmsh22-bin', 'msh', 'Gmsh 2.2 binary'], ['gmsh40', 'msh', 'Gmsh 4.0'],
    ['dolfin', 'xml', 'DOLFIN XML'], ['meshb', 'meshb', 'Medit binary'],
];
// written only over a file of their own: offered for a job uploaded in them
const OWN_ONLY = [['abaqus', 'inp', 'Abaqus'], ['netgen', 'vol', 'Netgen']];

function stat(k, v) {
    return el('div', { class: 'stat' }, el('div', { class: 'k', text: k }), el('div', { class: 'v', text: v }));
}

function jobView(id) {
    const ctl = new AbortController();
    const st = { id, job: null, recs: [], report: null, stopped: false, drawQueued: false, timer: 0 };
    document.title = 'qdcd · job ' + short(id);
    $('job-id').textContent = id;
    $('job-state').textContent = '';
    $('job-state').className = 'state';
    $('job-meta').textContent = 'loading…';
    $('job-options-text').textContent = '';
    $('job-error').hidden = true;
    $('job-notes').hidden = true;
    $('job-stats').replaceChildren();
    $('report-card').hidden = true;
    $('downloads-card').hidden = true;
    $('view3d-card').hidden = true;
    $('view3d').hidden = true;
    $('view3d-layers').hidden = true;
    $('view3d-load').hidden = false;
    $('view3d-status').textContent = VIEW3D_HELP;
    $('chart').dataset.points = '0';
    $('hist').dataset.drawn = '0';
    const chartRedraw = () => {
        if (st.drawQueued) return;
        st.drawQueued = true;
        requestAnimationFrame(() => {
            st.drawQueued = false;
            drawChart($('chart'), st.recs);
            const last = st.recs[st.recs.length - 1];
            $('chart').dataset.points = String(st.recs.length);
            document.dispatchEvent(new CustomEvent('qdc:chart', { detail: { points: st.recs.length, seq: last ? last.seq : -1 } }));
            renderStats(st);
        });
    };
    st.redraw = chartRedraw;
    $('job-cancel').onclick = () => jobAction(id, 'cancel').then(() => loadJob(st));
    $('job-delete').onclick = () => jobAction(id, 'delete').then(() => go('/'));
    const onResize = () => { chartRedraw(); if (st.report) drawHist($('hist'), st.report, $('hist-log').checked); };
    window.addEventListener('resize', onResize);
    $('hist-log').onchange = onResize;
    $('view3d-load').onclick = () => load3d(st);
    // the header (state, elapsed, cancel requested) every 2 s until the job ends
    const header = async () => {
        if (st.stopped || (st.job && st.job.done)) return;
        if (!document.hidden && st.job) await loadJob(st);
        st.headerTimer = setTimeout(header, 2000);
    };
    (async () => {
        if (!(await loadJob(st))) return;
        st.headerTimer = setTimeout(header, 2000);
        await follow(st, ctl.signal);
    })();
    return {
        name: 'job',
        stop: () => {
            st.stopped = true;
            ctl.abort();
            clearTimeout(st.timer);
            clearTimeout(st.headerTimer);
            window.removeEventListener('resize', onResize);
            if (st.gl) st.gl.stop();
        },
    };
}

async function loadJob(st) {
    try {
        st.job = await apiJSON('/v1/jobs/' + st.id);
    } catch (e) {
        if (e.status === 404) {
            $('job-meta').textContent = 'There is no job ' + st.id + ' (or it belongs to another token).';
            $('job-state').textContent = 'not found';
            return false;
        }
        $('job-meta').textContent = String(e.message || e);
        return false;
    }
    if (st.stopped) return false;
    renderJob(st);
    if (st.job.done && !st.report && !st.reportLoading && st.job.links.report) {
        st.reportLoading = true;
        loadReport(st).finally(() => { st.reportLoading = false; });
    }
    return true;
}

function renderJob(st) {
    const j = st.job;
    $('job-state').textContent = j.state + (j.cancel_requested && !j.done ? ' (cancelling)' : '');
    $('job-state').className = 'state ' + j.state;
    $('job-cancel').hidden = j.done;
    const o = j.options || {};
    const meta = [
        j.mesh.format + (j.mesh.surface ? ' surface' : ''), bytes(j.mesh.bytes),
        int(j.mesh.vertices) + ' vertices', int(j.mesh.tets) + ' tets',
        'submitted ' + when(j.created), 'elapsed ' + elapsed(j),
        j.attempts > 1 ? j.attempts + ' attempts' : null,
        j.stop_reason ? 'stopped: ' + j.stop_reason : null,
    ].filter(Boolean);
    $('job-meta').textContent = meta.join(' · ');
    $('job-options-text').textContent = Object.entries(o).map(([k, v]) => k + '=' + v).join(' ');
    if (j.error) {
        $('job-error').textContent = describeProblem(j.error.status, j.error);
        $('job-error').hidden = false;
    }
    if (j.notes && j.notes.length) {
        $('job-notes').replaceChildren(...j.notes.map((n) => el('li', { text: n })));
        $('job-notes').hidden = false;
    }
    renderStats(st);
    if (j.links.result) renderDownloads(st);
}

function renderStats(st) {
    const r = st.recs.length ? st.recs[st.recs.length - 1] : st.job && st.job.progress;
    const r0 = st.recs[0];
    if (!r) {
        $('job-stats').replaceChildren(stat('state', st.job ? st.job.state : '…'));
        return;
    }
    $('job-stats').replaceChildren(
        stat('iteration', r.iteration + ' · ' + r.phase),
        stat('mean ratio', (r0 ? fix(r0.mean_ratio_mean, 4) + ' → ' : '') + fix(r.mean_ratio_mean, 4)),
        stat('worst', (r0 ? sgn(r0.mean_ratio_min, 3) + ' → ' : '') + sgn(r.mean_ratio_min, 3)),
        stat('dihedral', fix(r.dihedral_min, 1) + '°..' + fix(r.dihedral_max, 1) + '°'),
        stat('inverted', (r0 ? int(r0.n_inverted) + ' → ' : '') + int(r.n_inverted)),
        stat('run time', dur(r.elapsed)));
}

// Follow /events with fetch() (EventSource cannot send a token), parsing the
// stream by hand; reconnect after the last seq if the stream breaks.
async function follow(st, signal) {
    let after = -1;
    let run = 0; // the job's attempt the records so far are of
    for (let attempt = 0; !st.stopped; attempt++) {
        let ended = false;
        try {
            // with attempt=, a job run again since (its node died) starts over
            const q = '?after=' + after + (run ? '&attempt=' + run : '');
            const res = await api('/v1/jobs/' + st.id + '/events' + q, { signal, headers: { Accept: 'text/event-stream' } });
            if (!res.ok) throw problem(res.status, await res.json().catch(() => null));
            const reader = res.body.getReader();
            const dec = new TextDecoder();
            let buf = '';
            for (;;) {
                const { value, done } = await reader.read();
                if (done) break;
                buf += dec.decode(value, { stream: true }).replace(/\r\n?/g, '\n');
                let i;
                while ((i = buf.indexOf('\n\n')) >= 0) {
                    const block = buf.slice(0, i);
                    buf = buf.slice(i + 2);
                    const ev = { event: 'message', data: '' };
                    for (const line of block.split('\n')) {
                        if (!line || line[0] === ':') continue;
                        const c = line.indexOf(':');
                        const k = c < 0 ? line : line.slice(0, c);
                        const v = c < 0 ? '' : line.slice(c + 1).replace(/^ /, '');
                        if (k === 'data') ev.data += (ev.data ? '\n' : '') + v;
                        else ev[k] = v;
                    }
                    if (ev.event === 'restart') { // the records start over
                        st.recs = [];
                        after = -1;
                        st.redraw();
                    } else if (ev.event === 'progress') {
                        const rec = JSON.parse(ev.data);
                        after = rec.seq;
                        run = rec.attempt || run;
                        st.recs.push(rec);
                        st.redraw();
                        if (st.job && st.job.state === 'queued') { // it started: say so now
                            st.job.state = 'running';
                            loadJob(st);
                        }
                    } else if (ev.event === 'end') {
                        ended = true;
                    }
                }
            }
        } catch (e) {
            if (st.stopped || (e && e.name === 'AbortError')) return;
            if (e.status === 404) { await loadJob(st); return; }
        }
        if (st.stopped) return;
        if (ended) {
            await loadJob(st);
            return;
        }
        await new Promise((r) => { st.timer = setTimeout(r, Math.min(5000, 500 * (attempt + 1))); });
        loadJob(st);
    }
}

async function loadReport(st) {
    try {
        st.report = await apiJSON('/v1/jobs/' + st.id + '/report');
    } catch (e) {
        return;
    }
    if (st.stopped) return;
    renderReport(st);
}

function kvTable(t, head, rows) {
    t.replaceChildren(el('thead', {}, el('tr', {}, ...head.map((h, i) => el('th', { class: i ? 'num' : '', text: h })))),
        el('tbody', {}, ...rows.map((r) => el('tr', {}, ...r.map((c, i) => el('td', { class: i ? 'num' : '', text: c }))))));
}

function renderReport(st) {
    const r = st.report;
    const b = r.before || {};
    const a = r.after || {};
    $('report-card').hidden = false;
    drawHist($('hist'), r, $('hist-log').checked);
    kvTable($('quality-table'), ['', 'before', 'after'], [
        ['mean ratio: mean', fix(b.mean_ratio_mean, 4), fix(a.mean_ratio_mean, 4)],
        ['mean ratio: worst', sgn(b.mean_ratio_min, 4), sgn(a.mean_ratio_min, 4)],
        ['volume-length: mean', fix(b.volume_length_mean, 4), fix(a.volume_length_mean, 4)],
        ['condition number: max', fix(b.condition_number_max, 3), fix(a.condition_number_max, 3)],
        ['smallest dihedral', fix(b.dihedral_min, 2) + '°', fix(a.dihedral_min, 2) + '°'],
        ['largest dihedral', fix(b.dihedral_max, 2) + '°', fix(a.dihedral_max, 2) + '°'],
        ['inverted tets', int(b.n_inverted), int(a.n_inverted)],
    ]);
    const th = [];
    for (const d of [5, 15, 30, 40]) th.push(['smallest angle < ' + d + '°', int(b['n_dmin_lt_' + d]), int(a['n_dmin_lt_' + d])]);
    for (const d of [175, 165, 150, 140]) th.push(['largest angle > ' + d + '°', int(b['n_dmax_gt_' + d]), int(a['n_dmax_gt_' + d])]);
    kvTable($('threshold-table'), ['tets', 'before', 'after'], th);
    const be = r.boundary_error || {};
    const pct = (x) => (typeof x === 'number' ? (100 * x).toPrecision(3) + '%' : '');
    const run = r.run || {};
    const abs = (x) => (typeof x === 'number' ? x.toPrecision(4) : '–');
    const rel = (x) => (typeof x === 'number' && be.bbox_diagonal > 0 ? pct(x / be.bbox_diagonal) : '');
    kvTable($('boundary-table'), ['', 'absolute', '% of diagonal'], [
        ['Hausdorff', abs(be.hausdorff), pct(be.hausdorff_rel)],
        ['mean', abs(be.mean), pct(be.mean_rel)],
        ['rms', abs(be.rms), pct(be.rms_rel)],
        ['vertex off the surface (max)', abs(be.vertex_max), pct(be.vertex_max_rel)],
        // hausd=H|P%|rel:F bounds the distance; auto (with slide) bounds how far a vertex leaves the surface
        run.hausd_bound ? ['bound (hausd)', abs(run.hausd_bound), rel(run.hausd_bound)]
            : run.lift_bound ? ['bound (auto: vertex off the surface)', abs(run.lift_bound), rel(run.lift_bound)]
                : ['bound (hausd)', 'none', ''],
    ]);
    const sec = run.seconds || {};
    kvTable($('run-table'), ['', ''], [
        ['outcome', (run.outcome || '–') + (run.stop_reason ? ' (' + run.stop_reason + ')' : '')],
        ['iterations', String(run.iterations) + (run.best_iteration !== undefined ? ', best record ' + run.best_iteration : '')],
        ['solver', run.solver || '–'],
        ...(run.held_back ? [['vertices held back at their input position', int(run.held_back)]] : []),
        ...(run.topology ? [['topology: tets', int(run.topology.tets_in) + ' → ' + int(run.topology.tets_out)],
            ['topology: operations', int(run.topology.edge_removals) + ' edges removed, ' + int(run.topology.flips23) +
                ' 2-3 flips, ' + int(run.topology.multiface_removals) + ' multi-face removals, ' +
                int(run.topology.rounds) + ' rounds']] : []),
        ...Object.entries(sec).map(([k, v]) => [k + ' time', dur(v)]),
    ]);
}

function renderDownloads(st) {
    const box = $('downloads');
    if (box.dataset.id === st.id) return;
    box.dataset.id = st.id;
    const base = '/v1/jobs/' + st.id;
    // the upload's own format: the uploaded file with the new coordinates,
    // everything else it holds (names, tags, arrays) kept
    // (topology other than none: new tets, so qdc's own writer in every
    // format, and Abaqus and Netgen, written only over the upload, not offered)
    const own = st.job.mesh.format;
    const newTets = (st.job.options || {}).topology && st.job.options.topology !== 'none';
    const formats = FORMATS.concat(OWN_ONLY.filter(([f]) => f === own));
    // a format that shares its extension with an earlier one is named in the file name
    const first = (ext) => formats.find(([, e]) => e === ext)[0];
    const items = (what, tag) => formats.filter(([f]) => what === 'input' || !newTets || !OWN_ONLY.some(([o]) => o === f))
        .map(([f, ext, label]) => [base + '/' + what + '?format=' + f,
            'qdc-' + short(st.id) + tag + (first(ext) !== f ? '-' + f : '') + '.' + ext, label, f]);
    const links = (list, spliced) => list.map(([href, name, label, f]) =>
        el('a', { class: 'button small', href, download: name, 'data-format': f,
            text: f === own && spliced ? label + ' (as uploaded)' : label,
            title: f === own && spliced ? 'the uploaded file with only the coordinates replaced: names, tags and arrays kept'
                : f === own ? "new tets: written by qdc's own writer (vertices, tets, triangles and their region tags)" : undefined,
            onclick: (ev) => authDownload(ev, href, name) }));
    const res = items('result', '');
    res.push([base + '/report', 'qdc-' + short(st.id) + '-report.json', 'report (JSON)', 'report']);
    box.replaceChildren(...links(res, !newTets));
    $('downloads-input').replaceChildren(...links(items('input', '-input'), true));
    $('downloads-card').hidden = false;
    $('view3d-card').hidden = false;
    const nt = st.job.mesh.tets;
    if (nt && nt <= AUTO_3D_TETS && !st.gl) load3d(st);
    else if (nt > AUTO_3D_TETS && nt <= MAX_3D_TETS && !st.gl)
        $('view3d-status').textContent = int(nt) + ' tets: the 3D view loads the input and the result (about 2 × ' +
            Math.round((24 * st.job.mesh.vertices + 16 * nt) / 1048576) + ' MiB) and finds their boundary and worst tets when asked.';
}

// A plain link cannot carry the token: with one, fetch the file and save it
// from a blob URL.
async function authDownload(ev, href, name) {
    if (!token()) return;
    ev.preventDefault();
    try {
        const res = await api(href);
        if (!res.ok) throw problem(res.status, await res.json().catch(() => null));
        const url = URL.createObjectURL(await res.blob());
        const a = el('a', { href: url, download: name });
        document.body.append(a);
        a.click();
        a.remove();
        setTimeout(() => URL.revokeObjectURL(url), 10000);
    } catch (e) {
        alertError(e);
    }
}

// ------------------------------------------------------------------- charts --

const COLORS = ['#1f6feb', '#cf222e', '#8250df', '#bf8700', '#57606a'];
const PHASE_FILL = { input: '#eef1f4', pre: '#fff8e1', global: '#ffffff', finish: '#eaf5ea', angles: '#f3ecfb', rerun: '#fde8e8',
    topology: '#e3f2fd' };

function setupCanvas(c) {
    const dpr = window.devicePixelRatio || 1;
    const w = c.clientWidth;
    const h = c.clientHeight;
    if (c.width !== Math.round(w * dpr) || c.height !== Math.round(h * dpr)) {
        c.width = Math.round(w * dpr);
        c.height = Math.round(h * dpr);
    }
    const g = c.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    g.font = '11px system-ui, sans-serif';
    return { g, w, h };
}

function niceTicks(lo, hi, n) {
    if (!(hi > lo)) { hi = lo + 1; }
    const raw = (hi - lo) / n;
    const p = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 2.5, 5, 10].map((m) => m * p).find((s) => s >= raw) || raw;
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(+v.toPrecision(12));
    return out;
}

// Three panels sharing the x axis (progress records in order): mean ratio
// (mean, worst), dihedral extremes (degrees), inverted tets; phases shaded.
function drawChart(c, recs) {
    const { g, w, h } = setupCanvas(c);
    const L = 46, R = 12, T = 18, B = 22, gap = 14; // phase names above the panels
    const ph = h - T - B - 2 * gap;
    const panels = [
        { top: T, h: ph * 0.42, series: [['mean_ratio_mean', 0], ['mean_ratio_min', 1]], label: 'mean ratio' },
        { top: 0, h: ph * 0.38, series: [['dihedral_min', 2], ['dihedral_max', 3]], label: 'dihedral °', lo: 0, hi: 180 },
        { top: 0, h: ph * 0.20, series: [['n_inverted', 4]], label: 'inverted', lo: 0 },
    ];
    panels[1].top = panels[0].top + panels[0].h + gap;
    panels[2].top = panels[1].top + panels[1].h + gap;
    const n = recs.length;
    const xmax = Math.max(1, n - 1);
    const X = (i) => L + (w - L - R) * (i / xmax);
    g.lineWidth = 1;
    if (!n) {
        g.fillStyle = '#5d6878';
        g.fillText('waiting for the first progress record…', L + 8, T + 20);
        return;
    }
    // phase bands
    for (let i = 0; i < n;) {
        let k = i;
        while (k + 1 < n && recs[k + 1].phase === recs[i].phase) k++;
        const x0 = X(Math.max(0, i - 0.5));
        const x1 = X(Math.min(xmax, k + 0.5));
        g.fillStyle = PHASE_FILL[recs[i].phase] || '#f6f8fa';
        g.fillRect(x0, T, Math.max(1, x1 - x0), h - T - B);
        if (x1 - x0 > 34) {
            g.fillStyle = '#8a94a3';
            g.fillText(recs[i].phase, x0 + 3, T - 5);
        }
        i = k + 1;
    }
    for (const p of panels) {
        let lo = p.lo, hi = p.hi;
        if (lo === undefined || hi === undefined) {
            let mn = Infinity, mx = -Infinity;
            for (const r of recs) for (const [k] of p.series) {
                const v = r[k];
                if (typeof v === 'number' && isFinite(v)) { mn = Math.min(mn, v); mx = Math.max(mx, v); }
            }
            if (p.series[0][0] === 'mean_ratio_mean') { // in [-1, 1]: tenths around the data
                lo = Math.floor(mn * 10) / 10;
                hi = Math.min(1, Math.ceil(mx * 10) / 10);
                if (hi - lo < 0.1) lo = hi - 0.1;
            } else {
                if (lo === undefined) lo = mn;
                if (hi === undefined) hi = Math.max(mx, 1);
            }
        }
        const Y = (v) => p.top + p.h - (p.h * (v - lo)) / (hi - lo || 1);
        g.strokeStyle = '#dde1e7';
        g.fillStyle = '#5d6878';
        g.textAlign = 'right';
        const ticks = p.lo === 0 && p.hi === 180 ? [0, 45, 90, 135, 180] : niceTicks(lo, hi, p.h > 90 ? 4 : 2);
        for (const t of ticks) {
            if (t < lo - 1e-9 || t > hi + 1e-9) continue;
            const y = Math.round(Y(t)) + 0.5;
            g.beginPath(); g.moveTo(L, y); g.lineTo(w - R, y); g.stroke();
            // kept inside the panel: a bottom label does not run into the next panel's top one
            g.fillText(String(t), L - 4, Math.max(p.top + 9, Math.min(p.top + p.h - 1, y + 4)));
        }
        g.textAlign = 'left';
        g.fillText(p.label, L + 4, p.top + 11);
        g.strokeStyle = '#b8c0cc';
        g.strokeRect(L + 0.5, p.top + 0.5, w - L - R, p.h);
        for (const [k, ci] of p.series) {
            g.strokeStyle = COLORS[ci];
            g.fillStyle = COLORS[ci];
            g.lineWidth = 1.8;
            g.beginPath();
            let started = false;
            for (let i = 0; i < n; i++) {
                const v = recs[i][k];
                if (typeof v !== 'number' || !isFinite(v)) continue;
                const x = X(i), y = Y(Math.max(lo, Math.min(hi, v)));
                if (started) g.lineTo(x, y); else { g.moveTo(x, y); started = true; }
            }
            g.stroke();
            if (n <= 60) for (let i = 0; i < n; i++) {
                const v = recs[i][k];
                if (typeof v !== 'number') continue;
                g.beginPath(); g.arc(X(i), Y(Math.max(lo, Math.min(hi, v))), 2.2, 0, 7); g.fill();
            }
            g.lineWidth = 1;
        }
    }
    // x axis: record numbers
    g.fillStyle = '#5d6878';
    g.textAlign = 'center';
    for (const t of niceTicks(0, xmax, Math.max(2, Math.floor((w - L - R) / 70)))) {
        if (t !== Math.round(t)) continue;
        g.fillText(String(t), X(t), h - 6);
    }
    g.textAlign = 'left';
}

// Before/after dihedral histograms (1° bins), bars side by side per bin.
function drawHist(c, r, log) {
    const { g, w, h } = setupCanvas(c);
    const hb = (r.before && r.before.dihedral_histogram) || [];
    const ha = (r.after && r.after.dihedral_histogram) || [];
    const L = 54, R = 10, T = 10, B = 22;
    const f = (v) => (log ? Math.log10(1 + v) : v);
    const mx = Math.max(1, ...hb.map(f), ...ha.map(f));
    const nb = Math.max(hb.length, ha.length, 180);
    const bw = (w - L - R) / nb;
    const Y = (v) => T + (h - T - B) * (1 - f(v) / mx);
    g.strokeStyle = '#dde1e7';
    g.fillStyle = '#5d6878';
    g.textAlign = 'right';
    const ticks = log ? [0, 1, 10, 100, 1e3, 1e4, 1e5, 1e6, 1e7].filter((v) => f(v) <= mx) : niceTicks(0, mx, 4);
    for (const t of ticks) {
        const y = Math.round(Y(t)) + 0.5;
        g.beginPath(); g.moveTo(L, y); g.lineTo(w - R, y); g.stroke();
        g.fillText(t >= 1e6 ? t / 1e6 + 'M' : t >= 1e3 ? t / 1e3 + 'k' : String(t), L - 4, y + 4);
    }
    g.textAlign = 'center';
    for (let d = 0; d <= 180; d += 30) {
        const x = L + (w - L - R) * (d / 180);
        g.beginPath(); g.moveTo(x + 0.5, T); g.lineTo(x + 0.5, h - B); g.stroke();
        g.fillText(d + '°', x, h - 6);
    }
    g.textAlign = 'left';
    const bar = (hist, color, off) => {
        g.fillStyle = color;
        for (let i = 0; i < hist.length; i++) {
            if (!hist[i]) continue;
            const y = Y(hist[i]);
            g.fillRect(L + i * bw + off * bw / 2, y, Math.max(1, bw / 2), h - B - y);
        }
    };
    bar(hb, '#9aa4b2', 0);
    bar(ha, '#1f6feb', 1);
    c.dataset.drawn = String(hb.length + ha.length);
}

// ------------------------------------------------------------------ 3D view --
// The result's boundary triangles (faces of exactly one tet), the input's
// worst tets (orange) and the result's (red) by mean ratio, in WebGL with no
// library; two checkboxes show or hide each set. Optional: without WebGL the
// card says so and the rest of the page is unaffected.

const MAX_3D_TETS = 3000000;
const VIEW3D_HELP = document.getElementById('view3d-status').textContent;
const AUTO_3D_TETS = 300000; // loaded with the page up to this size, on request above

async function fetchQmesh(st, what) {
    const res = await api('/v1/jobs/' + st.id + '/' + what + '?format=qmesh');
    if (!res.ok) throw problem(res.status, await res.json().catch(() => null));
    return parseQmesh(await res.arrayBuffer());
}

async function load3d(st) {
    const status = $('view3d-status');
    const nt = st.job.mesh.tets;
    $('view3d-load').hidden = true;
    if (nt > MAX_3D_TETS) {
        status.textContent = 'The 3D view is off above ' + int(MAX_3D_TETS) + ' tets.';
        return;
    }
    const canvas = $('view3d');
    // preserveDrawingBuffer: the picture can be read back (a screenshot, a test)
    const gl = canvas.getContext('webgl', { antialias: true, preserveDrawingBuffer: true });
    if (!gl) {
        status.textContent = 'No WebGL in this browser: the 3D view is not available (everything else is).';
        return;
    }
    status.textContent = 'loading the input and the result (' + int(nt) + ' tets each)…';
    const t0 = performance.now();
    const [inp, out] = await Promise.allSettled([fetchQmesh(st, 'input'), fetchQmesh(st, 'result')]);
    if (out.status === 'rejected') {
        status.textContent = 'The 3D view could not load the result: ' + (out.reason.message || out.reason);
        return;
    }
    if (st.stopped) return;
    const t1 = performance.now();
    const result = out.value;
    const frame = unitFrame(result);
    const surf = surfaceTriangles(result, frame);
    const after = worstTets(result, frame);
    const before = inp.status === 'fulfilled' && inp.value.nt ? worstTets(inp.value, frame) : null;
    canvas.hidden = false;
    $('view3d-layers').hidden = false;
    $('view3d-before').disabled = !before;
    st.gl = viewer(canvas, gl, [
        { name: 'before', data: before ? before.buf : new Float32Array(0), color: [0.98, 0.58, 0.1, 1], box: $('view3d-before') },
        { name: 'after', data: after.buf, color: [0.95, 0.16, 0.16, 1], box: $('view3d-after') },
        { name: 'surface', data: surf.buf, color: [0.75, 0.82, 0.92, 0.35], blend: true },
    ]);
    const ms = (t) => Math.round(t) + ' ms';
    status.textContent = int(surf.n) + ' boundary triangles of the result; ' +
        (before ? 'in orange the input\'s ' + before.n + ' worst tets (mean ratio ≤ ' + sgn(before.q, 3) + '), '
            : 'the input is not available (' + (inp.reason && (inp.reason.message || inp.reason)) + '), ') +
        'in red the result\'s ' + after.n + ' worst (≤ ' + sgn(after.q, 3) + '). Drag to rotate, wheel or pinch to zoom. (' +
        ms(t1 - t0) + ' to load, ' + ms(performance.now() - t1) + ' to build)';
}

function parseQmesh(buf) {
    const dv = new DataView(buf);
    const magic = new TextDecoder().decode(new Uint8Array(buf, 0, 7));
    if (buf.byteLength < 32 || magic !== 'QDCMESH') throw new Error('not a QMESH file');
    const nv = Number(dv.getBigUint64(16, true));
    const nt = Number(dv.getBigUint64(24, true));
    if (32 + 24 * nv + 16 * nt > buf.byteLength) throw new Error('QMESH file too short');
    // little-endian hosts (all WebGL platforms in practice): typed views directly
    const xyz = new Float64Array(buf, 32, 3 * nv);
    const tets = new Int32Array(buf, 32 + 24 * nv, 4 * nt);
    return { nv, nt, xyz, tets };
}

function meanRatio(x, a, b, c, d) {
    const ax = x[3 * a], ay = x[3 * a + 1], az = x[3 * a + 2];
    const ux = x[3 * b] - ax, uy = x[3 * b + 1] - ay, uz = x[3 * b + 2] - az;
    const vx = x[3 * c] - ax, vy = x[3 * c + 1] - ay, vz = x[3 * c + 2] - az;
    const wx = x[3 * d] - ax, wy = x[3 * d + 1] - ay, wz = x[3 * d + 2] - az;
    const det = ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx);
    const sq = (px, py, pz) => px * px + py * py + pz * pz;
    const l2 = sq(ux, uy, uz) + sq(vx, vy, vz) + sq(wx, wy, wz) + sq(vx - ux, vy - uy, vz - uz) +
        sq(wx - ux, wy - uy, wz - uz) + sq(wx - vx, wy - vy, wz - vz);
    if (!(l2 > 0)) return 0;
    const q = (12 * Math.cbrt(Math.pow(3 * Math.abs(det) / 6, 2))) / l2;
    return det < 0 ? -q : q;
}

// The faces of a tet, outward for a positive one.
const FACES = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

// Bounding box -> the cube [-1, 1]^3 around the origin (both meshes use the
// result's, so the input's tets land where they were).
function unitFrame(m) {
    const mn = [Infinity, Infinity, Infinity], mx = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < m.nv; i++) for (let k = 0; k < 3; k++) {
        const v = m.xyz[3 * i + k];
        if (v < mn[k]) mn[k] = v;
        if (v > mx[k]) mx[k] = v;
    }
    const ctr = [0, 1, 2].map((k) => (mn[k] + mx[k]) / 2);
    const sc = 2 / Math.max(mx[0] - mn[0], mx[1] - mn[1], mx[2] - mn[2], 1e-300);
    return { ctr, sc };
}

// Append triangle a b c of mesh m (flat normal) to out at o: 3 x (xyz, normal).
function putTri(out, o, m, fr, a, b, c) {
    const x = m.xyz, p = [];
    for (const v of [a, b, c]) p.push((x[3 * v] - fr.ctr[0]) * fr.sc, (x[3 * v + 1] - fr.ctr[1]) * fr.sc, (x[3 * v + 2] - fr.ctr[2]) * fr.sc);
    const ux = p[3] - p[0], uy = p[4] - p[1], uz = p[5] - p[2];
    const vx = p[6] - p[0], vy = p[7] - p[1], vz = p[8] - p[2];
    let nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const l = Math.hypot(nx, ny, nz) || 1;
    nx /= l; ny /= l; nz /= l;
    for (let k = 0; k < 3; k++) {
        out[o++] = p[3 * k]; out[o++] = p[3 * k + 1]; out[o++] = p[3 * k + 2];
        out[o++] = nx; out[o++] = ny; out[o++] = nz;
    }
    return o;
}

// The boundary: faces bucketed by their smallest vertex; a face seen once.
function surfaceTriangles(m, fr) {
    const { nv, nt, tets } = m;
    const F = FACES;
    const cnt = new Int32Array(nv + 1);
    for (let t = 0; t < nt; t++) for (let f = 0; f < 4; f++) {
        const a = tets[4 * t + F[f][0]], b = tets[4 * t + F[f][1]], c = tets[4 * t + F[f][2]];
        cnt[Math.min(a, b, c) + 1]++;
    }
    for (let i = 0; i < nv; i++) cnt[i + 1] += cnt[i];
    const pos = cnt.slice(0, nv);
    const fb = new Int32Array(4 * nt), fc = new Int32Array(4 * nt), fid = new Int32Array(4 * nt);
    for (let t = 0; t < nt; t++) for (let f = 0; f < 4; f++) {
        const a = tets[4 * t + F[f][0]], b = tets[4 * t + F[f][1]], c = tets[4 * t + F[f][2]];
        const lo = Math.min(a, b, c), hi = Math.max(a, b, c), mid = a + b + c - lo - hi;
        const k = pos[lo]++;
        fb[k] = mid; fc[k] = hi; fid[k] = 4 * t + f;
    }
    const surf = [];
    const seen = new Uint8Array(4 * nt);
    for (let v = 0; v < nv; v++) {
        for (let i = cnt[v]; i < cnt[v + 1]; i++) {
            if (seen[i]) continue;
            let twin = -1;
            for (let k = i + 1; k < cnt[v + 1]; k++)
                if (!seen[k] && fb[k] === fb[i] && fc[k] === fc[i]) { twin = k; break; }
            if (twin >= 0) seen[twin] = 1; else surf.push(fid[i]);
        }
    }
    const buf = new Float32Array(surf.length * 18);
    let o = 0;
    for (const fidx of surf) {
        const t = fidx >> 2, f = fidx & 3;
        o = putTri(buf, o, m, fr, tets[4 * t + F[f][0]], tets[4 * t + F[f][1]], tets[4 * t + F[f][2]]);
    }
    return { buf, n: surf.length };
}

// The worst tets by mean ratio (0.2% of them, 10 to 200), as their four faces.
// Candidates below a threshold taken from a 1024-bin histogram, so only a few
// are sorted even on a million tets.
function worstTets(m, fr) {
    const { nt, xyz, tets } = m;
    const q = new Float64Array(nt);
    const bins = new Int32Array(1024);
    const bin = (v) => Math.max(0, Math.min(1023, Math.floor((v + 1) * 512)));
    for (let t = 0; t < nt; t++) {
        q[t] = meanRatio(xyz, tets[4 * t], tets[4 * t + 1], tets[4 * t + 2], tets[4 * t + 3]);
        bins[bin(q[t])]++;
    }
    const n = Math.min(nt, Math.max(10, Math.min(200, Math.ceil(nt * 0.002))));
    let last = 0;
    for (let acc = 0; last < 1024 && (acc += bins[last]) < n; last++);
    const cand = [];
    for (let t = 0; t < nt; t++) if (bin(q[t]) <= last) cand.push(t);
    cand.sort((i, j) => q[i] - q[j]);
    const worst = cand.slice(0, n);
    const buf = new Float32Array(worst.length * 4 * 18);
    let o = 0;
    for (const t of worst) for (const f of FACES)
        o = putTri(buf, o, m, fr, tets[4 * t + f[0]], tets[4 * t + f[1]], tets[4 * t + f[2]]);
    return { buf, n: worst.length, q: worst.length ? q[worst[worst.length - 1]] : NaN };
}

// 4x4 column-major matrices
function mul(a, b) {
    const o = new Float32Array(16);
    for (let i = 0; i < 4; i++) for (let j = 0; j < 4; j++) {
        let s = 0;
        for (let k = 0; k < 4; k++) s += a[k * 4 + j] * b[i * 4 + k];
        o[i * 4 + j] = s;
    }
    return o;
}

function perspective(fovy, aspect, near, far) {
    const f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
    return new Float32Array([f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0]);
}

function rotation(yaw, pitch) {
    const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    const ry = new Float32Array([cy, 0, -sy, 0, 0, 1, 0, 0, sy, 0, cy, 0, 0, 0, 0, 1]);
    const rx = new Float32Array([1, 0, 0, 0, 0, cp, sp, 0, 0, -sp, cp, 0, 0, 0, 0, 1]);
    return mul(rx, ry);
}

// layers: [{name, data (Float32Array of xyz+normal), color [r,g,b,a], blend,
// box (a checkbox that shows/hides it)}]; opaque layers are drawn first.
function viewer(canvas, gl, layers) {
    const vs = 'attribute vec3 p; attribute vec3 n; uniform mat4 mvp; uniform mat4 rot; varying vec3 vn;' +
        'void main() { gl_Position = mvp * vec4(p, 1.0); vn = (rot * vec4(n, 0.0)).xyz; }';
    const fs = 'precision mediump float; varying vec3 vn; uniform vec4 color;' +
        'void main() { float l = abs(normalize(vn).z); gl_FragColor = vec4(color.rgb * (0.35 + 0.65 * l), color.a); }';
    const sh = (type, src) => {
        const s = gl.createShader(type);
        gl.shaderSource(s, src);
        gl.compileShader(s);
        return s;
    };
    const prog = gl.createProgram();
    gl.attachShader(prog, sh(gl.VERTEX_SHADER, vs));
    gl.attachShader(prog, sh(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(prog);
    gl.useProgram(prog);
    const P = gl.getAttribLocation(prog, 'p'), N = gl.getAttribLocation(prog, 'n');
    const U = { mvp: gl.getUniformLocation(prog, 'mvp'), rot: gl.getUniformLocation(prog, 'rot'), color: gl.getUniformLocation(prog, 'color') };
    const mk = (data) => { const b = gl.createBuffer(); gl.bindBuffer(gl.ARRAY_BUFFER, b); gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW); return { b, n: data.length / 6 }; };
    const bufs = layers.map((l) => Object.assign(mk(l.data), l));
    const cam = { yaw: 0.6, pitch: 0.4, dist: 3.0 };
    let queued = false, stopped = false;
    const bind = (buf) => {
        gl.bindBuffer(gl.ARRAY_BUFFER, buf.b);
        gl.enableVertexAttribArray(P);
        gl.vertexAttribPointer(P, 3, gl.FLOAT, false, 24, 0);
        gl.enableVertexAttribArray(N);
        gl.vertexAttribPointer(N, 3, gl.FLOAT, false, 24, 12);
    };
    const draw = () => {
        queued = false;
        if (stopped) return;
        const dpr = window.devicePixelRatio || 1;
        const w = Math.round(canvas.clientWidth * dpr), h = Math.round(canvas.clientHeight * dpr);
        if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
        gl.viewport(0, 0, w, h);
        gl.clearColor(0.063, 0.086, 0.122, 1);
        gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
        const rot = rotation(cam.yaw, cam.pitch);
        const view = mul(new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -cam.dist, 1]), rot);
        const mvp = mul(perspective(0.8, w / Math.max(1, h), 0.05, 50), view);
        gl.uniformMatrix4fv(U.mvp, false, mvp);
        gl.uniformMatrix4fv(U.rot, false, rot);
        gl.enable(gl.DEPTH_TEST);
        const shown = bufs.filter((l) => l.n && (!l.box || l.box.checked));
        const opaque = shown.some((l) => !l.blend);
        for (const l of shown) {
            gl.depthMask(!l.blend);
            if (l.blend) {
                gl.enable(gl.BLEND);
                gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
            } else {
                gl.disable(gl.BLEND);
            }
            bind(l);
            // alone, the surface is drawn nearly opaque
            gl.uniform4f(U.color, l.color[0], l.color[1], l.color[2], l.blend && !opaque ? 0.9 : l.color[3]);
            gl.drawArrays(gl.TRIANGLES, 0, l.n);
        }
        gl.depthMask(true);
        canvas.dataset.layers = shown.map((l) => l.name + ':' + l.n / 3).join(' ');
        const surf = bufs.find((l) => l.name === 'surface');
        canvas.dataset.triangles = String(surf ? surf.n / 3 : 0);
    };
    const redraw = () => { if (!queued) { queued = true; requestAnimationFrame(draw); } };
    const ptrs = new Map();
    let pinch = 0;
    canvas.onpointerdown = (e) => { canvas.setPointerCapture(e.pointerId); ptrs.set(e.pointerId, [e.clientX, e.clientY]); };
    canvas.onpointerup = canvas.onpointercancel = (e) => { ptrs.delete(e.pointerId); pinch = 0; };
    canvas.onpointermove = (e) => {
        const p = ptrs.get(e.pointerId);
        if (!p) return;
        if (ptrs.size === 1) {
            cam.yaw += (e.clientX - p[0]) * 0.01;
            cam.pitch = Math.max(-1.55, Math.min(1.55, cam.pitch + (e.clientY - p[1]) * 0.01));
        }
        ptrs.set(e.pointerId, [e.clientX, e.clientY]);
        if (ptrs.size === 2) {
            const [a, b] = [...ptrs.values()];
            const d = Math.hypot(a[0] - b[0], a[1] - b[1]);
            if (pinch) cam.dist = Math.max(0.5, Math.min(20, cam.dist * pinch / d));
            pinch = d;
        }
        redraw();
    };
    canvas.addEventListener('wheel', (e) => {
        e.preventDefault();
        cam.dist = Math.max(0.5, Math.min(20, cam.dist * Math.exp(e.deltaY * 0.001)));
        redraw();
    }, { passive: false });
    window.addEventListener('resize', redraw);
    for (const l of layers) if (l.box) l.box.onchange = redraw;
    redraw();
    return { stop: () => { stopped = true; window.removeEventListener('resize', redraw); } };
}

// --------------------------------------------------------------------- init --

function init() {
    $('token-form').addEventListener('submit', tokenEntered);
    $('token-dialog').addEventListener('cancel', (e) => e.preventDefault());
    $('forget').hidden = !token();
    $('forget').onclick = () => { sessionStorage.removeItem(TOKEN_KEY); location.reload(); };
    $('file').addEventListener('change', (e) => chooseFile(e.target.files[0]));
    const drop = $('drop');
    drop.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('over'); });
    drop.addEventListener('dragleave', () => drop.classList.remove('over'));
    drop.addEventListener('drop', (e) => {
        e.preventDefault();
        drop.classList.remove('over');
        if (e.dataTransfer.files.length) chooseFile(e.dataTransfer.files[0]);
    });
    $('submit-form').addEventListener('submit', submit);
    for (const b of $('filters').querySelectorAll('button')) {
        b.addEventListener('click', () => {
            listState.filter = b.dataset.state;
            for (const o of $('filters').querySelectorAll('button')) o.classList.toggle('on', o === b);
            renderJobs();
        });
    }
    route();
}

init();
