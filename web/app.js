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

// A job's name: its label, else the uploaded file's name, else its short id.
const jobName = (j) => (j && (j.label || j.file_name)) || short(j ? j.id : '');

// The stem of the uploaded file's name (bunny_low_10k.mesh.gz -> bunny_low_10k)
// for download names, or qdc-<short id> when the upload had no name.
function fileStem(j) {
    let n = (j.file_name || '').replace(/^.*[\\/]/, '').replace(/\.gz$/i, '');
    if (n.includes('.')) n = n.slice(0, n.lastIndexOf('.'));
    n = n.replace(/[^A-Za-z0-9._+-]+/g, '_').replace(/^[._]+/, '');
    return n || 'qdc-' + short(j.id);
}

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
let hoverState = () => null; // the job view's state, for the charts' tooltips

function route() {
    if (view && view.stop) view.stop();
    const m = location.pathname.match(/^\/ui\/jobs\/([0-9a-f]{32})$/);
    const c = location.pathname === '/' && compareIds(location.hash);
    $('view-list').hidden = !!(m || c);
    $('view-job').hidden = !m;
    $('view-compare').hidden = !c;
    if (m) view = jobView(m[1]);
    else if (c) view = compareView(c);
    else view = listView();
    view.key = location.pathname + location.hash;
}

function go(path) {
    if (path !== location.pathname + location.hash) history.pushState(null, '', path);
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
// a hash typed or followed by hand (#compare/ID/ID); popstate has routed a
// history step already
window.addEventListener('hashchange', () => { if (!view || view.key !== location.pathname + location.hash) route(); });

// ------------------------------------------------------------ other tabs --
// Every open tab follows deletions and state changes: the views poll the API
// (which also sees what curl or another machine did), and a tab that deletes,
// cancels or submits tells the others of this origin at once. The message
// names the job only: each tab fetches what it shows with its own token.

const tabs = typeof BroadcastChannel === 'function' ? new BroadcastChannel('qdc-jobs') : null;

function tellTabs(kind, id) {
    if (tabs) tabs.postMessage({ kind, id });
}

if (tabs) {
    tabs.onmessage = (ev) => {
        const m = ev.data;
        if (m && typeof m.id === 'string' && view && view.onNews) view.onNews(m);
    };
}
// a tab that comes back to the front looks at once (its timers idle while hidden)
document.addEventListener('visibilitychange', () => {
    if (!document.hidden && view && view.onNews) view.onNews({ kind: 'visible', id: '' });
});

// ---------------------------------------------------------------- job list --

// The options the form offers: their types, valid values, defaults and help
// come from GET /v1/options (the library's table, as `qdc options` prints it),
// so a new default shows here without touching the page.
const MAIN_OPTIONS = ['metric', 'boundary', 'hausd', 'topology', 'max_iter', 'stall', 'mode', 'time_limit',
    'finish', 'angle_polish', 'tetgen_quality'];
let OPTIONS = []; // the table's entries named in MAIN_OPTIONS, in that order

// The formats come from GET /v1/formats (the library's format table), so a
// new format shows here without touching the page: the format an upload's
// extension names (the first of its family), those a result can be written
// in, and those written only over an upload of their own.
let FMT = null; // {meshExt, surfExt, results, ownOnly}
let formatsLoading = null;
function loadFormats() {
    if (FMT) return Promise.resolve(FMT);
    formatsLoading = formatsLoading || apiJSON('/v1/formats').then((b) => {
        const meshExt = {}, surfExt = {};
        for (const f of b.formats) if (f.upload && !(f.extension in meshExt)) meshExt[f.extension] = f.name;
        for (const f of b.surfaces) surfExt[f.extension] = f.name;
        const item = (f) => [f.name, f.extension, shortHelp(f.about)];
        FMT = { meshExt, surfExt, results: b.formats.filter((f) => f.result).map(item),
            ownOnly: b.formats.filter((f) => f.upload && f.splice && !f.result).map(item) };
        return FMT;
    }).finally(() => { formatsLoading = null; });
    return formatsLoading;
}

// filter: the state shown (all when empty); find: text in the name, label,
// file name or id; sort: a column and a direction; ticked: the (at most two)
// jobs picked for comparison
const listState = { filter: '', find: '', sort: { key: 'created', dir: 'desc' }, ticked: [],
    jobs: [], first: new Map(), firstBusy: new Set() };
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

// The .h5 file an XDMF text keeps its heavy data in (its Format="HDF"
// DataItems read "FILE.h5:/dataset"), or '' if its data is inline.
function xdmfH5Name(text) {
    const m = /<DataItem\b[^>]*\bFormat\s*=\s*["']HDF["'][^>]*>\s*([^<:]+):/i.exec(text);
    return m ? m[1].trim() : '';
}

function chooseError(text) {
    chosen = null;
    $('submit-btn').disabled = true;
    $('file-info').textContent = '';
    $('submit-error').textContent = text;
    $('submit-error').hidden = false;
}

// A picked file, gunzipped here when its name ends in .gz (the name without it).
async function gunzipped(f) {
    if (!/\.gz$/i.test(f.name)) return f;
    const blob = await new Response(f.stream().pipeThrough(new DecompressionStream('gzip'))).blob();
    return new File([blob], f.name.slice(0, -3));
}

// Files picked or dropped: one mesh, or an .xdmf (.xmf) with the .h5 it names
// (sent together as multipart/form-data, parts "xdmf" and "h5"; either may
// be gzipped: gunzipped here first).
async function chooseFiles(list) {
    let files = Array.from(list || []);
    const isX = (f) => /\.(xdmf|xmf)(\.gz)?$/i.test(f.name);
    $('submit-error').hidden = true;
    if (files.length < 2 && !(files.length === 1 && isX(files[0])))
        return chooseFile(files[0]);
    const picked = files;
    try {
        files = files.length <= 2 ? await Promise.all(files.map(gunzipped)) : files;
    } catch (e) {
        return chooseError('cannot gunzip ' + picked.map((f) => f.name).join(' or ') + ': ' + (e.message || e));
    }
    const xdmf = files.filter((f) => /\.(xdmf|xmf)$/i.test(f.name));
    const h5 = files.filter((f) => /\.(h5|hdf5)$/i.test(f.name));
    if (files.length > 2 || xdmf.length !== 1 || (files.length === 2 && h5.length !== 1))
        return chooseError('Pick one mesh file, or an .xdmf file together with its .h5 file.');
    let want = '';
    try {
        want = xdmfH5Name(await xdmf[0].text());
    } catch (e) {
        return chooseError('cannot read ' + xdmf[0].name + ': ' + (e.message || e));
    }
    if (!want) { // inline XDMF: one file as any other (gunzipped at upload)
        if (files.length === 2)
            return chooseError(xdmf[0].name + ' keeps its data inline: pick it alone, without ' + h5[0].name + '.');
        return chooseFile(picked[0]);
    }
    if (!h5.length)
        return chooseError(xdmf[0].name + ' keeps its data in ' + want +
            ': pick (or drop) the .xdmf and ' + want + ' together.');
    chooseFile(xdmf[0], h5[0]);
}

function chooseFile(file, h5) {
    $('submit-error').hidden = true;
    if (!file) return;
    if (!FMT) { // the table first (a file picked before it loaded)
        loadFormats().then(() => chooseFile(file, h5)).catch((e) => {
            $('submit-error').textContent = 'The format table (GET /v1/formats) did not load: ' + (e.message || e);
            $('submit-error').hidden = false;
        });
        return;
    }
    let name = file.name.toLowerCase();
    const gz = name.endsWith('.gz');
    if (gz) name = name.slice(0, -3);
    const ext = name.includes('.') ? name.slice(name.lastIndexOf('.') + 1) : '';
    const meshExt = FMT ? FMT.meshExt : {}, surfExt = FMT ? FMT.surfExt : {};
    const surface = ext in surfExt;
    if (h5) { // the format is the pair's: no format= in the query
        chosen = { file, h5, format: '', surface: false, gz: false };
        $('file-info').textContent = file.name + ' + ' + h5.name + ' · ' + bytes(file.size + h5.size) +
            ' · XDMF with its heavy data in HDF5, sent together';
        surfaceOptions(false);
        $('submit-btn').disabled = false;
        return;
    }
    chosen = { file, format: meshExt[ext] || surfExt[ext] || '', surface, gz };
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
    if (chosen.h5) { // the browser writes the multipart body and its boundary
        body = new FormData();
        body.append('xdmf', chosen.file, chosen.file.name);
        body.append('h5', chosen.h5, chosen.h5.name);
    }
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
    const q = new URLSearchParams(optionQuery());
    q.set('name', chosen.file.name);
    const label = $('label-input').value.trim();
    if (label) q.set('label', label);
    const url = '/v1/jobs?' + q.toString();
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
            $('label-input').value = '';
            tellTabs('submitted', r.body.id);
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
        // FormData: the browser sets multipart/form-data with its boundary
        const h = authHeaders(body instanceof FormData ? {} : { 'Content-Type': 'application/octet-stream' });
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

// The input's and the result's quality: a finished job's report (before and
// after: the result may be an earlier record than the last, when a rerun was
// not kept), else record 0 of its progress; fetched once per job and state.
function listFigures(j) {
    const s = listState;
    const key = j.id + (j.done ? ':done' : '');
    // a record (the input's is record 0: iterations 0) or the report to read
    if (s.first.has(key) || s.firstBusy.has(key) || !(j.progress || (j.done && j.links && j.links.report))) return;
    s.firstBusy.add(key);
    const got = j.done && j.links && j.links.report
        ? apiJSON(j.links.report).then((r) => ({ in: r.before, out: r.after }))
        : apiJSON('/v1/jobs/' + j.id + '/progress?after=-1').then((b) => (b.records.length ? { in: b.records[0] } : null));
    // no figures (no record yet, no report) is an answer too: asked again
    // only when the job's state changes, not on every drawing of the list
    got.then((f) => { s.first.set(key, f || {}); })
        .catch(() => { s.first.set(key, {}); })
        .finally(() => { s.firstBusy.delete(key); if (view && view.name === 'list') renderJobs(); });
}

// Delete asks first, in a dialog of the page (a native confirm() would stop
// the page's timers); true when the user confirmed.
function confirmDelete(id) {
    const d = $('confirm-dialog');
    $('confirm-text').textContent = 'Delete job ' + short(id) + '? Its input, result and report are removed from qdcd; this cannot be undone.';
    d.returnValue = '';
    d.showModal();
    d.querySelector('button[value="cancel"]').focus();
    return new Promise((resolve) => d.addEventListener('close', () => resolve(d.returnValue === 'ok'), { once: true }));
}

// Cancel or delete (after asking); false when the user kept the job.
async function jobAction(id, what) {
    if (what === 'delete' && !(await confirmDelete(id))) return false;
    try {
        if (what === 'cancel') await apiJSON('/v1/jobs/' + id + ':cancel', { method: 'POST' });
        else {
            const res = await api('/v1/jobs/' + id, { method: 'DELETE' });
            if (!res.ok && res.status !== 404) throw problem(res.status, await res.json().catch(() => null));
        }
        tellTabs(what === 'cancel' ? 'changed' : 'deleted', id);
    } catch (e) {
        alertError(e);
    }
    return true;
}

function alertError(e) {
    const box = $('view-job').hidden ? $('submit-error') : $('job-error');
    box.textContent = e.body ? describeProblem(e.status, e.body) : String(e.message || e);
    box.hidden = false;
}

function renderJobs() {
    const s = listState;
    const tbody = $('jobs').tBodies[0];
    const rows = listRows(s);
    const frag = document.createDocumentFragment();
    for (const j of rows) {
        listFigures(j);
        const fig = s.first.get(j.id + (j.done ? ':done' : '')) || s.first.get(j.id) || {};
        const f = fig.in;
        // a finished job's result is the report's (the last record may be a rerun
        // that was not kept): nothing shown until it is in
        const p = fig.out || (j.done && j.links && j.links.report ? null : j.progress);
        const acts = el('td', { class: 'actions' });
        if (!j.done)
            acts.append(el('button', { type: 'button', class: 'small', text: 'Cancel', 'data-act': 'cancel', 'aria-label': 'Cancel job ' + short(j.id),
                onclick: () => jobAction(j.id, 'cancel').then(refreshList) }));
        acts.append(el('button', { type: 'button', class: 'small danger', text: 'Delete', 'data-act': 'delete', 'aria-label': 'Delete job ' + short(j.id),
            onclick: () => jobAction(j.id, 'delete').then(refreshList) }));
        const tets = j.mesh.tets || (j.mesh.surface ? 'surface' : 0);
        frag.append(el('tr', { 'data-id': j.id, 'data-state': j.state },
            el('td', { class: 'name' }, tickBox(j), el('a', { href: '/ui/jobs/' + j.id, 'data-nav': true, class: j.label || j.file_name ? 'jobname' : 'id', text: jobName(j), title: (j.label || j.file_name ? jobName(j) + ' · ' : '') + j.id }),
                j.label && j.file_name ? el('span', { class: 'small muted', text: ' ' + j.file_name }) : null),
            el('td', {}, el('span', { class: 'state ' + j.state, text: j.state + (j.cancel_requested && !j.done ? ' (cancelling)' : '') })),
            el('td', { class: 'num', 'data-label': 'tets', text: typeof tets === 'number' ? int(tets) : tets }),
            el('td', { class: 'num opt wide', text: int(j.mesh.vertices) }),
            el('td', { class: 'opt wide', text: j.mesh.format + ' · ' + bytes(j.mesh.bytes) }),
            el('td', { class: 'num', 'data-label': 'mean ratio', text: (f ? fix(f.mean_ratio_mean, 4) : '–') + ' → ' + (p ? fix(p.mean_ratio_mean, 4) : '–') }),
            el('td', { class: 'num opt', text: (f ? fix(f.dihedral_min, 1) + '°' : '–') + ' → ' + (p ? fix(p.dihedral_min, 1) + '°' : '–') }),
            el('td', { class: 'num', 'data-label': 'elapsed', text: elapsed(j) }),
            el('td', { class: 'opt mid', text: when(j.created) }),
            acts));
    }
    // the rows are new each time: keep the keyboard's place (a tick or a button)
    const had = document.activeElement;
    const tr = had && tbody.contains(had) ? had.closest('tr') : null;
    const what = tr && (had.dataset.tick ? 'input.tick' : had.dataset.act ? 'button[data-act="' + had.dataset.act + '"]' : had.tagName === 'A' ? 'a' : null);
    // the same rows as drawn: leave them (a click or a tick in progress stays put)
    const probe = document.createElement('tbody');
    probe.append(frag.cloneNode(true));
    if (probe.innerHTML !== tbody.innerHTML) tbody.replaceChildren(frag);
    if (what && !tbody.contains(had)) {
        const again = tbody.querySelector('tr[data-id="' + tr.dataset.id + '"] ' + what);
        if (again) again.focus();
    }
    $('jobs-empty').hidden = rows.length > 0;
    $('jobs-empty').textContent = !s.jobs.length ? 'No jobs yet: submit a mesh above.'
        : 'No ' + (s.filter ? s.filter + ' ' : '') + 'jobs' + (s.find ? ' matching "' + s.find + '"' : '') + '.';
    listTools(s, rows);
}

// The rows shown: the state filter, then the text, then the order chosen
// (ties: newest first).
function listRows(s) {
    const find = s.find.trim().toLowerCase();
    const hit = (j) => !find || [jobName(j), j.label, j.file_name, j.id].some((x) => x && x.toLowerCase().includes(find));
    const by = {
        name: (a, b) => jobName(a).localeCompare(jobName(b), 'en', { numeric: true, sensitivity: 'base' }),
        state: (a, b) => a.state.localeCompare(b.state),
        created: (a, b) => a.created - b.created,
    }[s.sort.key];
    const sign = s.sort.dir === 'desc' ? -1 : 1;
    return s.jobs.filter((j) => (!s.filter || j.state === s.filter) && hit(j))
        .sort((a, b) => sign * by(a, b) || b.created - a.created || (a.id < b.id ? -1 : 1));
}

// The compare tick of a row: a third tick drops the first.
function tickBox(j) {
    const s = listState;
    return el('input', { type: 'checkbox', class: 'tick', 'data-tick': j.id, 'aria-label': 'compare ' + jobName(j),
        title: 'tick two jobs, then Compare', checked: s.ticked.includes(j.id) ? 'checked' : null,
        onchange: (ev) => {
            s.ticked = s.ticked.filter((x) => x !== j.id);
            if (ev.target.checked) s.ticked.push(j.id);
            if (s.ticked.length > 2) s.ticked.shift();
            renderJobs();
        } });
}

// The sort headers (aria-sort), the sort menu, the count and the compare button.
function listTools(s, rows) {
    for (const th of $('jobs').tHead.querySelectorAll('th[data-sort]')) {
        const on = th.dataset.sort === s.sort.key;
        if (on) th.setAttribute('aria-sort', s.sort.dir === 'asc' ? 'ascending' : 'descending');
        else th.removeAttribute('aria-sort');
        th.querySelector('button').dataset.arrow = on ? (s.sort.dir === 'asc' ? '▲' : '▼') : '';
    }
    $('jobs-sort').value = s.sort.key + ':' + s.sort.dir;
    s.ticked = s.ticked.filter((id) => s.jobs.some((j) => j.id === id));
    $('compare-btn').disabled = s.ticked.length !== 2;
    $('compare-btn').textContent = 'Compare the 2 ticked jobs' + (s.ticked.length === 1 ? ' (1 ticked)' : '');
    const n = rows.length === s.jobs.length ? s.jobs.length + ' jobs' : rows.length + ' of ' + s.jobs.length + ' jobs';
    if ($('jobs-count').textContent !== n) $('jobs-count').textContent = n;
}

function sortBy(key, dir) {
    const s = listState;
    s.sort = { key, dir: dir || (s.sort.key === key ? (s.sort.dir === 'asc' ? 'desc' : 'asc') : key === 'created' ? 'desc' : 'asc') };
    renderJobs();
}

function listToolsInit() {
    for (const th of $('jobs').tHead.querySelectorAll('th[data-sort]')) {
        const b = el('button', { type: 'button', class: 'sort', title: 'sort by ' + th.textContent, onclick: () => sortBy(th.dataset.sort) });
        b.append(...th.childNodes);
        th.append(b);
    }
    $('jobs-sort').addEventListener('change', (ev) => { const [k, d] = ev.target.value.split(':'); sortBy(k, d); });
    $('jobs-find').addEventListener('input', (ev) => { listState.find = ev.target.value; renderJobs(); });
    $('compare-btn').addEventListener('click', () => {
        if (listState.ticked.length === 2) go('/#compare/' + listState.ticked.join('/'));
    });
    for (const b of $('filters').querySelectorAll('button')) b.setAttribute('aria-pressed', String(b.classList.contains('on')));
}

let refreshList = async () => {};

function listView() {
    let timer = 0;
    let stopped = false;
    buildOptions();
    loadFormats().catch(() => {}); // retried by chooseFile's next pick and the job view
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
    // another tab deleted, cancelled or submitted: look now
    const onNews = () => { if (!stopped) refreshList(); };
    return { name: 'list', onNews, stop: () => { stopped = true; clearTimeout(timer); } };
}

// ----------------------------------------------------------------- job view --


function stat(k, v) {
    return el('div', { class: 'stat' }, el('div', { class: 'k', text: k }), el('div', { class: 'v', text: v }));
}

function jobView(id) {
    const ctl = new AbortController();
    const st = { id, job: null, recs: [], report: null, stopped: false, drawQueued: false, timer: 0, ctl };
    st.reportDrawn = new Promise((resolve) => { st.reportDone = resolve; });
    document.title = 'qdcd · job ' + short(id);
    $('job-id').textContent = id;
    $('job-state').textContent = '';
    $('job-state').className = 'state';
    $('job-meta').textContent = 'loading…';
    $('job-options-text').textContent = '';
    $('job-error').hidden = true;
    $('job-notes').hidden = true;
    followReset();
    $('job-stats').replaceChildren();
    $('report-card').hidden = true;
    renderOutcome(null);
    $('downloads-card').hidden = true;
    $('view3d-card').hidden = true;
    $('view3d').hidden = true;
    $('view3d-layers').hidden = true;
    $('view3d-tools').hidden = true;
    $('view3d-pick').textContent = '';
    $('view3d-cut-info').textContent = '';
    $('view3d-load').hidden = false;
    $('view3d-status').textContent = VIEW3D_HELP;
    $('chart').dataset.points = '0';
    $('hist').dataset.drawn = '0';
    $('chart-notes').hidden = true;
    $('chart-notes').dataset.key = '';
    const chartRedraw = () => {
        if (st.drawQueued) return;
        st.drawQueued = true;
        requestAnimationFrame(() => {
            st.drawQueued = false;
            const notes = rerunNotes(st.recs, st.report);
            const best = notes.find((x) => x.best);
            st.chartGeom = drawChart($('chart'), st.recs, { log: $('chart-log').checked, best: best ? best.i : undefined });
            $('chart').setAttribute('aria-label', chartSummary(st.recs, notes));
            const key = notes.map((x) => x.text).join('|');
            if ($('chart-notes').dataset.key !== key) {
                $('chart-notes').dataset.key = key;
                $('chart-notes').replaceChildren(...notes.map((x) => el('li', { class: x.best ? 'kept' : 'rerun', text: x.text })));
                $('chart-notes').hidden = !notes.length;
            }
            const last = st.recs[st.recs.length - 1];
            $('chart').dataset.points = String(st.recs.length);
            document.dispatchEvent(new CustomEvent('qdc:chart', { detail: { points: st.recs.length, seq: last ? last.seq : -1 } }));
            renderStats(st);
        });
    };
    st.redraw = chartRedraw;
    $('job-cancel').onclick = () => jobAction(id, 'cancel').then(() => loadJob(st));
    $('job-delete').onclick = () => jobAction(id, 'delete').then((done) => { if (done) go('/'); });
    const onResize = () => { chartRedraw(); if (st.report) st.histGeom = drawHist($('hist'), st.report, $('hist-log').checked); };
    window.addEventListener('resize', onResize);
    $('hist-log').onchange = onResize;
    $('chart-log').onchange = chartRedraw;
    hoverState = () => st;
    $('view3d-load').onclick = () => load3d(st);
    // the header (state, elapsed, cancel requested) every 2 s until the job ends
    const header = async () => {
        if (st.stopped || st.gone || (st.job && st.job.done)) return;
        if (!document.hidden && st.job) await loadJob(st);
        st.headerTimer = setTimeout(header, 2000);
    };
    (async () => {
        if (!(await loadJob(st))) return;
        st.headerTimer = setTimeout(header, 2000);
        watchGone(st);
        await follow(st, ctl.signal);
    })();
    return {
        name: 'job',
        // another tab deleted or cancelled this job (or came to the front)
        onNews: (m) => { if (!st.stopped && !st.gone && st.job && (!m.id || m.id === id)) loadJob(st); },
        stop: () => {
            st.stopped = true;
            ctl.abort();
            clearTimeout(st.timer);
            clearTimeout(st.headerTimer);
            clearTimeout(st.goneTimer);
            window.removeEventListener('resize', onResize);
            if (st.gl) st.gl.stop();
        },
    };
}

async function loadJob(st) {
    try {
        st.job = await apiJSON('/v1/jobs/' + st.id);
    } catch (e) {
        if (e.status === 404 && st.job) { // it was here: deleted since
            if (!st.stopped) jobGone(st);
            return false;
        }
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
    $('job-name').textContent = j.label || j.file_name || '';
    $('job-name').hidden = !(j.label || j.file_name);
    document.title = 'qdcd · ' + jobName(j);
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
    // the result's figures once the report is there (the last record may be a
    // rerun that was not kept), the last record's before
    const res = (st.report && st.report.after) || r;
    if (!r) {
        $('job-stats').replaceChildren(stat('state', st.job ? st.job.state : '…'));
        return;
    }
    $('job-stats').replaceChildren(
        // iterations: the latest record's number, as qdc status and the report count them
        stat('iterations', (st.recs.length ? st.recs.length - 1 : r.iteration) + ' · ' + r.phase),
        stat('mean ratio', (r0 ? fix(r0.mean_ratio_mean, 4) + ' → ' : '') + fix(res.mean_ratio_mean, 4)),
        stat('worst', (r0 ? sgn(r0.mean_ratio_min, 3) + ' → ' : '') + sgn(res.mean_ratio_min, 3)),
        stat('dihedral', fix(res.dihedral_min, 1) + '°..' + fix(res.dihedral_max, 1) + '°'),
        stat('inverted', (r0 ? int(r0.n_inverted) + ' → ' : '') + int(res.n_inverted)),
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
                        restartNotice(ev.data);
                        st.recs = [];
                        after = -1;
                        st.redraw();
                    } else if (ev.event === 'progress') {
                        const rec = JSON.parse(ev.data);
                        after = rec.seq;
                        run = rec.attempt || run;
                        // opened after a takeover: say whose records these are
                        if (run > 1 && !$('job-follow').dataset.kind) runNotice(run);
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

// ------------------------------------------- the job page follows the job --
// #job-follow says what happened to the job behind the page's back: deleted
// (by another tab or client), or run again from the start (taken over after
// its node died or the daemon restarted).

function followReset() {
    $('job-follow').hidden = true;
    $('job-follow').textContent = '';
    delete $('job-follow').dataset.kind;
    $('job-delete').hidden = false;
}

function followSay(kind, text) {
    const p = $('job-follow');
    p.dataset.kind = kind;
    p.textContent = text;
    p.hidden = false;
}

// The SSE stream's `event: restart` ({from_attempt, attempt}).
function restartNotice(data) {
    let r = {};
    try { r = JSON.parse(data) || {}; } catch (e) { /* an empty restart still restarts */ }
    const from = r.from_attempt ? 'attempt ' + r.from_attempt : 'its run';
    followSay('restart', 'This job runs again from the start' + (r.attempt ? ': attempt ' + r.attempt : '') + ' (' + from +
        ' stopped: its node or the daemon went away). The chart starts over with the new run\'s records.');
    $('job-follow').dataset.attempt = String(r.attempt || '');
}

// A page opened after the job was taken over: its records are of a later run.
function runNotice(attempt) {
    followSay('attempt', 'This job ran again from the start: the chart shows attempt ' + attempt + ' (attempt ' + (attempt - 1) +
        ' stopped: its node or the daemon went away).');
    $('job-follow').dataset.attempt = String(attempt);
}

function jobGone(st) {
    if (st.gone) return;
    st.gone = true;
    st.ctl.abort();
    clearTimeout(st.goneTimer);
    $('job-state').textContent = 'deleted';
    $('job-state').className = 'state failed';
    $('job-cancel').hidden = true;
    $('job-delete').hidden = true;
    $('downloads-card').hidden = true;
    followSay('deleted', 'This job was deleted (in another tab or by another client): its input, result and report are gone from qdcd. ' +
        'What this page shows is what it had loaded.');
    document.title = 'qdcd · deleted: ' + jobName(st.job);
}

// Once the job has ended the header stops polling; a deletion elsewhere must
// still show: look every 3 s while the tab is in front (a 404 is the news).
function watchGone(st) {
    const tick = async () => {
        if (st.stopped || st.gone) return;
        if (!document.hidden && st.job && st.job.done) {
            try {
                const res = await api('/v1/jobs/' + st.id, { signal: st.ctl.signal });
                if (res.status === 404) jobGone(st);
                else if (res.ok) {
                    const j = await res.json();
                    if (j.state !== st.job.state || j.expired !== st.job.expired) loadJob(st);
                }
            } catch (e) { /* not answering: the next look */ }
        }
        if (!st.stopped && !st.gone) st.goneTimer = setTimeout(tick, 3000);
    };
    st.goneTimer = setTimeout(tick, 3000);
}

async function loadReport(st) {
    try {
        st.report = await apiJSON('/v1/jobs/' + st.id + '/report');
        if (!st.stopped) {
            renderReport(st);
            renderOutcome(st.report.outcome);
        }
    } catch (e) {
        /* no report: the rest of the view stands */
    } finally {
        // one frame later, so that the report's drawing is on screen first
        requestAnimationFrame(() => st.reportDone());
    }
}

// The outcome in words: the report's texts as they are (lib/eval/outcome.c
// makes them; no rule of its own here): the summary, then the warnings and
// suggestions in an alert when much is left bad.
function renderOutcome(o) {
    const box = $('job-outcome'), warn = $('outcome-warning');
    box.hidden = !(o && o.summary);
    if (box.hidden) return;
    $('outcome-summary').textContent = 'Outcome: ' + o.summary;
    const w = o.warnings || [], s = o.suggestions || [];
    warn.hidden = !w.length;
    warn.replaceChildren(...(w.length ? [el('strong', { text: 'Warning: ' + w.join('; ') + '.' }),
        el('ul', {}, ...s.map((t) => el('li', { text: 'Suggestion: ' + t })))] : []));
}

function kvTable(t, head, rows) {
    // an empty first header is named for screen readers
    const th = (h, i) => (h ? el('th', { class: i ? 'num' : '', text: h }) : el('th', {}, el('span', { class: 'vh', text: i ? 'value' : 'measure' })));
    t.replaceChildren(el('thead', {}, el('tr', {}, ...head.map(th))),
        el('tbody', {}, ...rows.map((r) => el('tr', {}, ...r.map((c, i) => el('td', { class: i ? 'num' : '', text: c }))))));
}

function renderReport(st) {
    const r = st.report;
    const b = r.before || {};
    const a = r.after || {};
    $('report-card').hidden = false;
    st.histGeom = drawHist($('hist'), r, $('hist-log').checked);
    $('hist').setAttribute('aria-label', histSummary(r));
    st.redraw(); // the chart marks the record kept
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
        // the bound (--hausd, or auto's under slide) is on this same distance:
        // the row right under it (a row of its own keeps the table narrow)
        ['Hausdorff', abs(be.hausdorff), pct(be.hausdorff_rel)],
        ['its bound', run.hausd_bound ? abs(run.hausd_bound) : 'none', run.hausd_bound ? rel(run.hausd_bound) : ''],
        ['mean', abs(be.mean), pct(be.mean_rel)],
        ['rms', abs(be.rms), pct(be.rms_rel)],
        ['vertex off the surface (max)', abs(be.vertex_max), pct(be.vertex_max_rel)],
    ]);
    const sec = run.seconds || {};
    kvTable($('run-table'), ['', ''], [
        ['outcome', (run.outcome || '–') + (run.stop_reason ? ' (' + run.stop_reason + ')' : '')],
        // one count (docs/defaults.md): the last record's number, as qdc status counts
        ['iterations', String(run.iterations)],
        ...(run.best_iteration !== undefined ? [['result from iteration', String(run.best_iteration)]] : []),
        ...(run.global_iterations !== undefined ? [['of them global', String(run.global_iterations)]] : []),
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
    if (!FMT) {
        loadFormats().then(() => renderDownloads(st)).catch(() => {});
        return;
    }
    box.dataset.id = st.id;
    const base = '/v1/jobs/' + st.id;
    // the upload's own format: the uploaded file with the new coordinates,
    // everything else it holds (names, tags, arrays) kept
    // (topology other than none: new tets, so qdc's own writer in every
    // format; a format written only over the upload, none today, not offered)
    const own = st.job.mesh.format;
    const newTets = (st.job.options || {}).topology && st.job.options.topology !== 'none';
    const formats = FMT.results.concat(FMT.ownOnly.filter(([f]) => f === own));
    // a format that shares its extension with an earlier one is named in the file name
    const first = (ext) => formats.find(([, e]) => e === ext)[0];
    const items = (what, tag) => formats.filter(([f]) => what === 'input' || !newTets || !FMT.ownOnly.some(([o]) => o === f))
        .map(([f, ext, label]) => [base + '/' + what + '?format=' + f,
            fileStem(st.job) + tag + (first(ext) !== f ? '-' + f : '') + '.' + ext, label, f]);
    const links = (list, spliced) => list.map(([href, name, label, f]) =>
        el('a', { class: 'button small', href, download: name, 'data-format': f,
            text: f === own && spliced ? label + ' (as uploaded)' : label,
            title: f === own && spliced ? 'the uploaded file with only the coordinates replaced: names, tags and arrays kept'
                : f === own ? "new tets: written by qdc's own writer (vertices, tets, triangles and their region tags)" : undefined,
            onclick: (ev) => authDownload(ev, href, name) }));
    const res = items('result', '.qdc');
    res.push([base + '/report', fileStem(st.job) + '.qdc-report.json', 'report (JSON)', 'report']);
    box.replaceChildren(...links(res, !newTets));
    if (st.job.mesh.h5 && !newTets) { // sent with an .h5: its .h5, which the .xdmf names result.h5
        const [a] = links([[base + '/result?format=h5', 'result.h5', 'HDF5 .h5 (of the .xdmf)', 'h5']], false);
        a.title = 'the uploaded .h5 with the new coordinates; the .xdmf names it result.h5: keep the two in one folder';
        box.insertBefore(a, box.lastChild);
    }
    $('downloads-input').replaceChildren(...links(items('input', '.input'), true));
    $('downloads-card').hidden = false;
    $('view3d-card').hidden = false;
    const nt = st.job.mesh.tets;
    // after the report is drawn: the 3D view's downloads and arithmetic do
    // not hold up the chart and the tables
    if (nt && nt <= AUTO_3D_TETS && !st.gl && !st.gl3dAsked) {
        st.gl3dAsked = true;
        st.reportDrawn.then(() => { if (!st.stopped && !st.gl) load3d(st); });
    }
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

// ------------------------------------------------------------ compare view --
// Two jobs side by side (/#compare/ID/ID), typically one input with different
// options: the options that differ marked, both quality tables (before and
// after), the boundary moved, both histograms on one scale. A job still
// running is looked at every 2 s until it ends; one deleted meanwhile is
// said so (another tab's news, or a 404 on the next look).

function compareIds(hash) {
    const m = hash.match(/^#compare\/([0-9a-f]{32})\/([0-9a-f]{32})$/);
    return m ? [m[1], m[2]] : null;
}

const AB = ['A', 'B'];

function compareView(ids) {
    const st = { ids, jobs: [null, null], reports: [null, null], gone: [false, false], stopped: false, timer: 0 };
    document.title = 'qdcd · compare';
    $('cmp-status').textContent = 'loading…';
    for (const t of ['cmp-heads', 'cmp-options', 'cmp-quality', 'cmp-boundary', 'cmp-run']) $(t).replaceChildren();
    $('cmp-input').textContent = '';
    for (const c of ['cmp-hist-a', 'cmp-hist-b']) $(c).dataset.drawn = '0';
    const look = async () => {
        clearTimeout(st.timer);
        for (let i = 0; i < 2; i++) {
            if (st.gone[i]) continue;
            try {
                st.jobs[i] = await apiJSON('/v1/jobs/' + ids[i]);
                if (st.jobs[i].done && st.jobs[i].links.report && !st.reports[i])
                    st.reports[i] = await apiJSON(st.jobs[i].links.report).catch(() => null);
            } catch (e) {
                if (e.status === 404) st.gone[i] = true;
                else if (e instanceof TypeError) setConn(false);
            }
        }
        if (st.stopped) return;
        renderCompare(st);
        const waiting = st.jobs.some((j, i) => !st.gone[i] && (!j || !j.done || (j.links.report && !st.reports[i])));
        st.timer = setTimeout(look, waiting ? 2000 : 3000);
    };
    look();
    return {
        name: 'compare',
        redraw: () => compareHists(st),
        onNews: (m) => { if (!st.stopped && (!m.id || ids.includes(m.id))) look(); },
        stop: () => { st.stopped = true; clearTimeout(st.timer); window.removeEventListener('resize', st.onResize); },
        st,
    };
}

// A table of rows [label, cells...] (a cell: text or a node, or {v, cls}); the
// first column heads its row. head: rows of [text, colspan] for <thead>.
function cmpTable(t, head, rows, rowClass) {
    const hrow = (r, k) => el('tr', {}, ...r.map(([x, span], i) => el('th', {
        scope: span > 1 ? 'colgroup' : 'col', colspan: span > 1 ? String(span) : null,
        class: (i && k === head.length - 1) ? 'num' : null }, x ? x : el('span', { class: 'vh', text: 'measure' }))));
    const cell = (c) => (c && typeof c === 'object' && !(c instanceof Node)
        ? el('td', { class: 'num ' + (c.cls || '') }, c.v, c.note ? el('span', { class: 'vh', text: ' ' + c.note }) : null)
        : el('td', { class: 'num' }, c));
    t.replaceChildren(el('thead', {}, ...head.map(hrow)),
        el('tbody', {}, ...rows.map((r, k) => el('tr', { class: rowClass ? rowClass(r, k) : null },
            el('th', { scope: 'row' }, r[0]), ...r.slice(1).map(cell)))));
}

// The quality rows: [label, key, format, +1 higher is better / -1 lower].
const CMP_QUALITY = [
    ['mean ratio: mean', 'mean_ratio_mean', (x) => fix(x, 4), 1],
    ['mean ratio: worst', 'mean_ratio_min', (x) => sgn(x, 4), 1],
    ['volume-length: mean', 'volume_length_mean', (x) => fix(x, 4), 1],
    ['condition number: max', 'condition_number_max', (x) => fix(x, 3), -1],
    ['smallest dihedral', 'dihedral_min', (x) => fix(x, 2) + '°', 1],
    ['largest dihedral', 'dihedral_max', (x) => fix(x, 2) + '°', -1],
    ['inverted tets', 'n_inverted', int, -1],
    ['tets: smallest angle < 5°', 'n_dmin_lt_5', int, -1],
    ['tets: smallest angle < 15°', 'n_dmin_lt_15', int, -1],
    ['tets: largest angle > 175°', 'n_dmax_gt_175', int, -1],
    ['tets: largest angle > 165°', 'n_dmax_gt_165', int, -1],
];

function renderCompare(st) {
    const [ja, jb] = st.jobs;
    const [ra, rb] = st.reports;
    const said = [];
    st.ids.forEach((id, i) => {
        const j = st.jobs[i];
        if (st.gone[i]) said.push('Job ' + AB[i] + ' (' + (j ? jobName(j) : short(id)) + ') ' + (j ? 'was deleted' : 'does not exist (or belongs to another token)') + '.');
        else if (j && !j.done) said.push('Job ' + AB[i] + ' is ' + j.state + ': its report comes when it ends.');
        else if (j && !st.reports[i]) said.push('Job ' + AB[i] + ' ' + j.state + ' with no report.');
    });
    if ($('cmp-status').textContent !== said.join(' ')) $('cmp-status').textContent = said.join(' ');
    document.title = 'qdcd · compare ' + st.ids.map((id, i) => (st.jobs[i] ? jobName(st.jobs[i]) : short(id))).join(' / ');
    $('cmp-heads').replaceChildren(...st.ids.map((id, i) => {
        const j = st.jobs[i];
        return el('div', { class: 'cmp-head', 'data-job': id },
            el('span', { class: 'ab', text: AB[i] }),
            j && !st.gone[i] ? el('a', { href: '/ui/jobs/' + id, 'data-nav': true, class: 'jobname', text: jobName(j), title: id })
                : el('span', { class: 'jobname', text: j ? jobName(j) : short(id) }),
            el('span', { class: 'state ' + (st.gone[i] ? 'failed' : j ? j.state : ''), text: st.gone[i] ? (j ? 'deleted' : 'not found') : j ? j.state : '…' }),
            j ? el('span', { class: 'small muted', text: ' ' + int(j.mesh.tets) + ' tets · submitted ' + when(j.created) }) : null);
    }));
    if (ja && jb) {
        const sameIn = ja.mesh.tets === jb.mesh.tets && ja.mesh.vertices === jb.mesh.vertices && ja.mesh.bytes === jb.mesh.bytes &&
            ja.mesh.format === jb.mesh.format && (!ra || !rb || ra.before.mean_ratio_mean === rb.before.mean_ratio_mean);
        $('cmp-input').textContent = sameIn
            ? 'Same input: ' + (ja.file_name || ja.mesh.format) + ', ' + int(ja.mesh.tets) + ' tets, ' + int(ja.mesh.vertices) + ' vertices.'
            : 'Different inputs: A ' + (ja.file_name || ja.mesh.format) + ' (' + int(ja.mesh.tets) + ' tets), B ' +
                (jb.file_name || jb.mesh.format) + ' (' + int(jb.mesh.tets) + ' tets): the figures compare different meshes.';
        $('cmp-input').className = sameIn ? 'small' : 'small warn';
        const oa = ja.options || {}, ob = jb.options || {};
        const keys = [...new Set([...Object.keys(oa), ...Object.keys(ob)])];
        const val = (o, k) => (k in o ? String(o[k]) : '–');
        const differ = keys.filter((k) => val(oa, k) !== val(ob, k));
        // the ones that differ first, marked (colour and a word)
        const rows = [...differ, ...keys.filter((k) => !differ.includes(k))].map((k) => differ.includes(k)
            ? [k, { v: val(oa, k), cls: 'diff', note: '(differs)' }, { v: val(ob, k), cls: 'diff', note: '(differs)' }]
            : [k, val(oa, k), val(ob, k)]);
        cmpTable($('cmp-options'), [[['option', 1], ['A', 1], ['B', 1]]], rows, (r, k) => (k < differ.length ? 'diff' : null));
        $('cmp-options').dataset.differ = differ.join(',');
        $('cmp-options').querySelector('tbody').setAttribute('aria-label', differ.length + ' options differ: ' + (differ.join(', ') || 'none'));
    }
    if (ra || rb) {
        const get = (r, side, k) => (r && r[side] ? r[side][k] : undefined);
        const rows = CMP_QUALITY.map(([label, k, f, dir]) => {
            const a = get(ra, 'after', k), b = get(rb, 'after', k);
            const better = typeof a === 'number' && typeof b === 'number' && a !== b ? ((a - b) * dir > 0 ? 0 : 1) : -1;
            const after = (x, i) => ({ v: typeof x === 'number' ? f(x) : '–', cls: better === i ? 'better' : '', note: better === i ? '(the better result)' : '' });
            return [label, typeof get(ra, 'before', k) === 'number' ? f(get(ra, 'before', k)) : '–', after(a, 0),
                typeof get(rb, 'before', k) === 'number' ? f(get(rb, 'before', k)) : '–', after(b, 1)];
        });
        cmpTable($('cmp-quality'), [[['', 1], ['A', 2], ['B', 2]], [['measure', 1], ['before', 1], ['after', 1], ['before', 1], ['after', 1]]], rows);
        const be = (r) => (r && r.boundary_error) || {};
        const abs = (x) => (typeof x === 'number' ? x.toPrecision(4) : '–');
        const pct = (x) => (typeof x === 'number' ? (100 * x).toPrecision(3) + '% of diagonal' : '');
        const two = (x, rel) => el('span', {}, abs(x), rel ? el('span', { class: 'sub muted', text: pct(rel) }) : null);
        const bnd = (r) => (r && r.run && r.run.hausd_bound) || 0;
        cmpTable($('cmp-boundary'), [[['', 1], ['A', 1], ['B', 1]]], [
            ['Hausdorff', two(be(ra).hausdorff, be(ra).hausdorff_rel), two(be(rb).hausdorff, be(rb).hausdorff_rel)],
            ['its bound', bnd(ra) ? abs(bnd(ra)) : 'none', bnd(rb) ? abs(bnd(rb)) : 'none'],
            ['mean', two(be(ra).mean, be(ra).mean_rel), two(be(rb).mean, be(rb).mean_rel)],
            ['rms', two(be(ra).rms, be(ra).rms_rel), two(be(rb).rms, be(rb).rms_rel)],
            ['vertex off the surface (max)', two(be(ra).vertex_max, be(ra).vertex_max_rel), two(be(rb).vertex_max, be(rb).vertex_max_rel)],
        ]);
        const run = (r) => (r && r.run) || {};
        const sec = (r) => run(r).seconds || {};
        cmpTable($('cmp-run'), [[['', 1], ['A', 1], ['B', 1]]], [
            ['outcome', ...[ra, rb].map((r) => (run(r).outcome || '–') + (run(r).stop_reason ? ' (' + run(r).stop_reason + ')' : ''))],
            ['iterations', ...[ra, rb].map((r) => (run(r).iterations !== undefined ? String(run(r).iterations) : '–'))],
            ['run time', ...[ra, rb].map((r) => dur(sec(r).total))],
        ]);
        compareHists(st);
    }
    if (!st.onResize) {
        st.onResize = () => compareHists(st);
        window.addEventListener('resize', st.onResize);
    }
}

// Both histograms on the scale of the larger.
function compareHists(st) {
    const log = $('cmp-hist-log').checked;
    const f = (v) => (log ? logc(v) : v);
    const top = Math.max(1, ...st.reports.flatMap((r) => (r ? [r.before, r.after] : []))
        .flatMap((x) => ((x && x.dihedral_histogram) || []).map(f)));
    st.reports.forEach((r, i) => {
        const c = $(i ? 'cmp-hist-b' : 'cmp-hist-a');
        $(c.id + '-h').textContent = AB[i] + (st.jobs[i] ? ': ' + jobName(st.jobs[i]) : '');
        if (!r) return;
        drawHist(c, r, log, top);
        c.setAttribute('aria-label', 'Job ' + AB[i] + '. ' + histSummary(r));
    });
}

// ------------------------------------------------------------------- charts --

const COLORS = ['#1f6feb', '#cf222e', '#8250df', '#9a6700', '#57606a'];
const PHASE_FILL = { input: '#eef1f4', pre: '#fff8e1', global: '#ffffff', finish: '#eaf5ea', angles: '#f3ecfb', rerun: '#fde8e8',
    topology: '#e3f2fd' };
const PHASE_NAME = {
    input: 'the input', pre: 'pre-iterations (before the harmonic field)', global: 'global iteration',
    finish: 'finishing sweep (worst tets, vertex by vertex)', angles: 'smallest-angle polish',
    rerun: 'rerun: restarted from the input',
    topology: 'topology: a round of flips (the tets change)',
};

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

const kfmt = (t) => (t >= 1e6 ? t / 1e6 + 'M' : t >= 1e3 ? t / 1e3 + 'k' : String(t));
// counts on a log scale: log10(1 + n), so that 0 stays at the bottom
const logc = (v) => Math.log10(1 + Math.max(0, v));
const LOG_TICKS = [0, 1, 10, 100, 1e3, 1e4, 1e5, 1e6, 1e7];

// The reruns of a run, in words: where each starts, what the run before it
// left, and which record the optimizer kept (the report's best_iteration).
function rerunNotes(recs, report) {
    const notes = [];
    for (let i = 1; i < recs.length; i++) {
        if (recs[i].phase !== 'rerun') continue;
        const prev = recs[i - 1];
        const why = prev.n_inverted > 0
            ? 'the run before ended with ' + int(prev.n_inverted) + ' tets inverted, so the optimizer started again from the input (' +
                int(recs[i].n_inverted) + ' inverted) with the boundary held differently (squashed ears held, the vertices around the inverted tets free, or no fold at the surface)'
            : 'the run before squashed ears of the surface, so the optimizer started again from the input with their corners held';
        notes.push({ i, text: 'Record ' + i + ': restarted from the input — ' + why + '. The jump back is the input again, not a regression: the best run is kept.' });
    }
    // the record that is the result: the report's run.best_iteration (a
    // record number of the whole run, reruns and topology rounds included);
    // a report without it (older daemons), the record with its figures
    const a = report && report.after, run = report && report.run;
    let k = run && Number.isInteger(run.best_iteration) ? recs.findIndex((r) => r.iteration === run.best_iteration) : -1;
    let dk = k >= 0 ? 0 : Infinity;
    if (k < 0 && a) for (let i = 0; i < recs.length; i++) {
        const r = recs[i];
        if (r.n_inverted !== a.n_inverted) continue;
        const d = Math.abs(r.mean_ratio_mean - a.mean_ratio_mean) + Math.abs(r.mean_ratio_min - a.mean_ratio_min);
        if (d < dk) { dk = d; k = i; }
    }
    if (k >= 0 && dk < 1e-4) {
        const runs = recs.slice(0, k + 1).filter((r) => r.phase === 'rerun').length;
        notes.push({ i: k, best: true, text: 'The result is record ' + k + (notes.length ? ', in the ' + ['first', 'second', 'third', 'fourth', 'fifth'][Math.min(runs, 4)] + ' run' : '') +
            ': mean ratio ' + fix(recs[k].mean_ratio_mean, 4) + ', worst ' + sgn(recs[k].mean_ratio_min, 3) + ', ' + int(recs[k].n_inverted) + ' inverted' +
            (k < recs.length - 1 ? ' (the records after it did not do better)' : '') + '.' });
    }
    return notes;
}

// Three panels sharing the x axis (progress records in order: 0 is the input,
// then one per global iteration, finishing sweep, polish round): mean ratio
// (mean, worst), dihedral extremes (degrees), inverted tets (count, log scale
// when asked); phases shaded, reruns marked and explained below the chart.
// Returns the geometry the hover needs.
function drawChart(c, recs, opt) {
    opt = opt || {};
    const { g, w, h } = setupCanvas(c);
    const L = 58, R = 12, T = 18, B = 36, gap = 16; // phase names above, axis title below
    const ph = h - T - B - 2 * gap;
    const panels = [
        { top: T, h: ph * 0.42, series: [['mean_ratio_mean', 0], ['mean_ratio_min', 1]], label: 'mean ratio', unit: '1 = regular tet' },
        { top: 0, h: ph * 0.36, series: [['dihedral_min', 2], ['dihedral_max', 3]], label: 'dihedral angle', unit: 'degrees', lo: 0, hi: 180 },
        { top: 0, h: ph * 0.22, series: [['n_inverted', 4]], label: 'inverted tets', unit: opt.log ? 'count, log scale' : 'count', lo: 0, log: !!opt.log },
    ];
    panels[1].top = panels[0].top + panels[0].h + gap;
    panels[2].top = panels[1].top + panels[1].h + gap;
    const n = recs.length;
    const xmax = Math.max(1, n - 1);
    const X = (i) => L + (w - L - R) * (i / xmax);
    const geom = { L, R, T, B, w, h, n, xmax, X, panels };
    g.lineWidth = 1;
    c.dataset.xlabel = 'progress record (0 = the input)';
    c.dataset.ylabels = panels.map((p) => p.label + ' (' + p.unit + ')').join('; ');
    if (!n) {
        g.fillStyle = '#5d6878';
        g.fillText('waiting for the first progress record…', L + 8, T + 20);
        return geom;
    }
    // phase bands; a rerun band gets a mark and its name
    for (let i = 0; i < n;) {
        let k = i;
        while (k + 1 < n && recs[k + 1].phase === recs[i].phase) k++;
        const x0 = X(Math.max(0, i - 0.5));
        const x1 = X(Math.min(xmax, k + 0.5));
        g.fillStyle = PHASE_FILL[recs[i].phase] || '#f6f8fa';
        g.fillRect(x0, T, Math.max(1, x1 - x0), h - T - B);
        if (x1 - x0 > 34) {
            g.fillStyle = '#5d6878';
            g.fillText(recs[i].phase, x0 + 3, T - 5);
        }
        if (recs[i].phase === 'rerun') {
            g.strokeStyle = '#cf222e';
            g.setLineDash([4, 3]);
            g.beginPath(); g.moveTo(Math.round(X(i)) + 0.5, T); g.lineTo(Math.round(X(i)) + 0.5, h - B); g.stroke();
            g.setLineDash([]);
            g.fillStyle = '#cf222e';
            g.fillText('↺ from the input', Math.min(X(i) + 3, w - R - 90), T + 12);
        }
        i = k + 1;
    }
    if (typeof opt.best === 'number' && opt.best >= 0 && opt.best < n) {
        const x = Math.round(X(opt.best)) + 0.5;
        g.strokeStyle = '#1a7f37';
        g.setLineDash([2, 2]);
        g.beginPath(); g.moveTo(x, T); g.lineTo(x, h - B); g.stroke();
        g.setLineDash([]);
        g.fillStyle = '#1a7f37';
        g.fillText('kept', Math.min(x + 3, w - R - 26), h - B - 4);
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
        const f = p.log ? logc : (v) => v;
        const flo = f(lo), fhi = p.log ? Math.max(logc(hi), 1) : hi;
        const Y = (v) => p.top + p.h - (p.h * (f(v) - flo)) / (fhi - flo || 1);
        p.Y = Y;
        p.lo = lo;
        p.hi = hi;
        g.strokeStyle = '#dde1e7';
        g.fillStyle = '#5d6878';
        g.textAlign = 'right';
        const ticks = p.log ? LOG_TICKS.filter((t) => t <= hi * 1.0001 || t === 0 || t === 1)
            : p.lo === 0 && p.hi === 180 ? [0, 45, 90, 135, 180] : niceTicks(lo, hi, p.h > 90 ? 4 : 2);
        for (const t of ticks) {
            if (f(t) < flo - 1e-9 || f(t) > fhi + 1e-9) continue;
            const y = Math.round(Y(t)) + 0.5;
            g.beginPath(); g.moveTo(L, y); g.lineTo(w - R, y); g.stroke();
            // kept inside the panel: a bottom label does not run into the next panel's top one
            g.fillText(p.log ? kfmt(t) : String(t), L - 4, Math.max(p.top + 9, Math.min(p.top + p.h - 1, y + 4)));
        }
        g.textAlign = 'left';
        const lab = p.label + ' (' + p.unit + ')';
        g.fillStyle = 'rgba(255, 255, 255, 0.85)';
        g.fillRect(L + 1, p.top + 1, g.measureText(lab).width + 7, 14);
        g.fillStyle = '#3d4756';
        g.fillText(lab, L + 4, p.top + 11);
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
    // x axis: record numbers and what they are
    g.fillStyle = '#5d6878';
    g.textAlign = 'center';
    for (const t of niceTicks(0, xmax, Math.max(2, Math.floor((w - L - R) / 70)))) {
        if (t !== Math.round(t)) continue;
        g.fillText(String(t), X(t), h - B + 13);
    }
    g.fillStyle = '#3d4756';
    const xl = c.dataset.xlabel + ': one per global iteration, finishing sweep or polish round';
    g.fillText(g.measureText(xl).width < w - 8 ? xl : c.dataset.xlabel, Math.max(L + (w - L - R) / 2, g.measureText(c.dataset.xlabel).width / 2 + 4), h - 5);
    g.textAlign = 'left';
    return geom;
}

// Text for a screen reader: what the chart shows, in numbers.
function chartSummary(recs, notes) {
    if (!recs.length) return 'Convergence chart: no progress record yet.';
    const a = recs[0], z = recs[recs.length - 1];
    const phases = [];
    for (const r of recs) if (!phases.length || phases[phases.length - 1][0] !== r.phase) phases.push([r.phase, 1]); else phases[phases.length - 1][1]++;
    return 'Convergence chart of ' + recs.length + ' progress records (' + phases.map(([p, k]) => p + (k > 1 ? ' ×' + k : '')).join(', ') + '). ' +
        'Mean ratio ' + fix(a.mean_ratio_mean, 4) + ' to ' + fix(z.mean_ratio_mean, 4) + '; worst ' + sgn(a.mean_ratio_min, 3) + ' to ' + sgn(z.mean_ratio_min, 3) +
        '; dihedral angles ' + fix(a.dihedral_min, 1) + '–' + fix(a.dihedral_max, 1) + ' to ' + fix(z.dihedral_min, 1) + '–' + fix(z.dihedral_max, 1) +
        ' degrees; inverted tets ' + int(a.n_inverted) + ' to ' + int(z.n_inverted) + '.' + (notes.length ? ' ' + notes.map((x) => x.text).join(' ') : '');
}

// The record under the pointer, in a tooltip (and a line over the canvas).
function chartHover(c, tip, line, getState) {
    const show = (ev) => {
        const { geom, recs } = getState();
        if (!geom || !recs.length) return;
        const rect = c.getBoundingClientRect();
        const x = ev.clientX - rect.left;
        const i = Math.max(0, Math.min(recs.length - 1, Math.round(((x - geom.L) / (geom.w - geom.L - geom.R)) * geom.xmax)));
        const r = recs[i];
        tip.replaceChildren(
            el('strong', { text: 'record ' + i }), ' · iteration ' + r.iteration + ' · ' + (PHASE_NAME[r.phase] || r.phase), el('br'),
            'mean ratio ' + fix(r.mean_ratio_mean, 4) + ' · worst ' + sgn(r.mean_ratio_min, 4), el('br'),
            'dihedral ' + fix(r.dihedral_min, 2) + '°..' + fix(r.dihedral_max, 2) + '° · inverted ' + int(r.n_inverted), el('br'),
            (typeof r.step === 'number' ? 'step ' + r.step.toPrecision(3) + ' · ' : '') + 'at ' + dur(r.elapsed));
        const px = geom.X(i);
        line.style.left = Math.round(px) + 'px';
        line.style.top = geom.T + 'px';
        line.style.height = (geom.h - geom.T - geom.B) + 'px';
        line.hidden = false;
        tip.hidden = false;
        tip.style.left = Math.round(px + 12 + 260 > rect.width ? px - 12 - tip.offsetWidth : px + 12) + 'px';
        tip.style.top = Math.round(Math.max(0, Math.min(rect.height - tip.offsetHeight, ev.clientY - rect.top - 20))) + 'px';
        c.dataset.hover = String(i);
    };
    const hide = () => { tip.hidden = true; line.hidden = true; delete c.dataset.hover; };
    c.addEventListener('pointermove', show);
    c.addEventListener('pointerdown', show);
    c.addEventListener('pointerleave', hide);
}

// Before/after dihedral histograms (1° bins): "before" a grey filled outline,
// "after" a blue line on top, so that each shows where the other is higher.
// Returns the geometry the hover needs.
// top: the y scale's top (in the scale's units) when larger than this
// histogram's own (two histograms drawn on one scale)
function drawHist(c, r, log, top) {
    const { g, w, h } = setupCanvas(c);
    const hb = (r.before && r.before.dihedral_histogram) || [];
    const ha = (r.after && r.after.dihedral_histogram) || [];
    const L = 58, R = 10, T = 10, B = 36;
    const f = (v) => (log ? logc(v) : v);
    const mx = Math.max(1, top || 0, ...hb.map(f), ...ha.map(f));
    const nb = Math.max(hb.length, ha.length, 180);
    const bw = (w - L - R) / nb;
    const Y = (v) => T + (h - T - B) * (1 - f(v) / mx);
    g.strokeStyle = '#dde1e7';
    g.fillStyle = '#5d6878';
    g.textAlign = 'right';
    const ticks = log ? LOG_TICKS.filter((v) => f(v) <= mx) : niceTicks(0, mx, 4);
    for (const t of ticks) {
        const y = Math.round(Y(t)) + 0.5;
        g.beginPath(); g.moveTo(L, y); g.lineTo(w - R, y); g.stroke();
        g.fillText(kfmt(t), L - 4, y + 4);
    }
    g.textAlign = 'center';
    for (let d = 0; d <= 180; d += 30) {
        const x = L + (w - L - R) * (d / 180);
        g.beginPath(); g.moveTo(x + 0.5, T); g.lineTo(x + 0.5, h - B); g.stroke();
        g.fillText(d + '°', x, h - B + 13);
    }
    g.fillStyle = '#3d4756';
    g.fillText('dihedral angle (degrees, 1° bins)', L + (w - L - R) / 2, h - 5);
    g.save();
    g.translate(12, T + (h - T - B) / 2);
    g.rotate(-Math.PI / 2);
    g.fillText(log ? 'angles per bin (log scale)' : 'angles per bin', 0, 0);
    g.restore();
    g.textAlign = 'left';
    const path = (hist) => {
        g.beginPath();
        g.moveTo(L, Y(0));
        for (let i = 0; i < nb; i++) {
            const y = Y(hist[i] || 0);
            g.lineTo(L + i * bw, y);
            g.lineTo(L + (i + 1) * bw, y);
        }
        g.lineTo(L + nb * bw, Y(0));
    };
    path(hb);
    g.fillStyle = 'rgba(154, 164, 178, 0.45)';
    g.fill();
    g.strokeStyle = '#6e7781';
    g.lineWidth = 1.2;
    g.stroke();
    path(ha);
    g.strokeStyle = '#1f6feb';
    g.lineWidth = 2;
    g.stroke();
    g.lineWidth = 1;
    c.dataset.drawn = String(hb.length + ha.length);
    c.dataset.log = log ? '1' : '0';
    return { L, R, T, B, w, h, nb, bw, hb, ha };
}

function histSummary(r) {
    const b = r.before || {}, a = r.after || {};
    const low = (hist, d) => (hist || []).slice(0, d).reduce((s, v) => s + v, 0);
    const high = (hist, d) => (hist || []).slice(d).reduce((s, v) => s + v, 0);
    return 'Histogram of all dihedral angles (six per tet), 1 degree bins, before and after. Smallest angle ' + fix(b.dihedral_min, 2) +
        ' to ' + fix(a.dihedral_min, 2) + ' degrees, largest ' + fix(b.dihedral_max, 2) + ' to ' + fix(a.dihedral_max, 2) + ' degrees. Angles under 10 degrees: ' +
        int(low(b.dihedral_histogram, 10)) + ' before, ' + int(low(a.dihedral_histogram, 10)) + ' after; over 170 degrees: ' +
        int(high(b.dihedral_histogram, 170)) + ' before, ' + int(high(a.dihedral_histogram, 170)) + ' after.';
}

function histHover(c, tip, getGeom) {
    c.addEventListener('pointermove', (ev) => {
        const gm = getGeom();
        if (!gm) return;
        const rect = c.getBoundingClientRect();
        const x = ev.clientX - rect.left;
        const i = Math.floor((x - gm.L) / gm.bw);
        if (i < 0 || i >= gm.nb) { tip.hidden = true; return; }
        tip.textContent = i + '°–' + (i + 1) + '°: ' + int(gm.hb[i] || 0) + ' angles before, ' + int(gm.ha[i] || 0) + ' after';
        tip.hidden = false;
        tip.style.left = Math.round(x + 12 + 240 > rect.width ? x - 12 - tip.offsetWidth : x + 12) + 'px';
        tip.style.top = Math.round(Math.max(0, ev.clientY - rect.top - 30)) + 'px';
        c.dataset.hover = String(i);
    });
    c.addEventListener('pointerleave', () => { tip.hidden = true; delete c.dataset.hover; });
}

// ------------------------------------------------------------------ 3D view --
// The result's boundary triangles (faces of exactly one tet), the input's
// worst tets (orange) and the result's (red) by mean ratio, in WebGL with no
// library; checkboxes show or hide each set. A clip plane (x, y or z) cuts
// the boundary away and draws the tets it cuts, coloured by their mean ratio;
// a click on a triangle or tet tells that tet's quality and angles. Fit and
// Reset frame the mesh. While turning, a lighter level of detail (half the
// resolution, at most LOD_TRIS boundary triangles) keeps the frame rate up.
// Optional: without WebGL the card says so and the rest of the page is
// unaffected.

const MAX_3D_TETS = 3000000;
const VIEW3D_HELP = document.getElementById('view3d-status').textContent;
const AUTO_3D_TETS = 300000; // loaded with the page up to this size, on request above
const LOD_TRIS = 60000; // boundary triangles drawn while turning, at most
const MAX_CUT_TETS = 300000;
const FLOATS = 9; // per vertex: xyz, normal, rgb

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
        canvas.setAttribute('aria-label', status.textContent);
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
    const input = inp.status === 'fulfilled' && inp.value.nt === result.nt ? inp.value : null;
    const frame = unitFrame(result);
    const q = qualities(result);
    const qin = input ? qualities(input) : null;
    const surf = surfaceTriangles(result, frame);
    const after = worstTets(result, q, frame);
    const before = qin ? worstTets(input, qin, frame) : null;
    const model = { result, input, frame, q, qin };
    if (input) model.moved = movedColours(surf, model);
    canvas.hidden = false;
    $('view3d-layers').hidden = false;
    $('view3d-tools').hidden = false;
    $('view3d-before').disabled = !before;
    const t2 = performance.now();
    st.gl = viewer(canvas, gl, model, [
        { name: 'before', data: before ? before.buf : new Float32Array(0), tet: before ? before.tet : new Int32Array(0), color: [0.98, 0.58, 0.1, 1], box: $('view3d-before'), clip: true },
        { name: 'after', data: after.buf, tet: after.tet, color: [0.95, 0.16, 0.16, 1], box: $('view3d-after'), clip: true },
        { name: 'cut', data: new Float32Array(0), tet: new Int32Array(0), vertexColor: true },
        { name: 'surface', data: surf.buf, tet: surf.tet, color: [0.75, 0.82, 0.92, 0.35], blend: true, clip: true, lod: true },
        { name: 'picked', data: new Float32Array(0), tet: new Int32Array(0), color: [0.2, 0.95, 1, 0.85], blend: true, onTop: true },
    ]);
    const ms = (t) => Math.round(t) + ' ms';
    const first = st.gl.firstFrame();
    canvas.dataset.firstFrameMs = String(Math.round(first - t0));
    const text = int(surf.n) + ' boundary triangles of the result; ' +
        (before ? 'in orange the input\'s ' + before.n + ' worst tets (mean ratio ≤ ' + sgn(before.q, 3) + '), '
            : 'the input is not available (' + (inp.reason ? inp.reason.message || inp.reason : 'another tet count') + '), ') +
        'in red the result\'s ' + after.n + ' worst (≤ ' + sgn(after.q, 3) + '). Drag to rotate, wheel or pinch to zoom, click a triangle or tet for its quality. (' +
        ms(t1 - t0) + ' to load, ' + ms(t2 - t1) + ' to build, first frame ' + ms(first - t0) + ' after the request' +
        (surf.n > LOD_TRIS ? '; while turning: 1 in ' + Math.ceil(surf.n / LOD_TRIS) + ' boundary triangles at half resolution' : '; while turning: half resolution') + ')';
    status.textContent = text;
    canvas.setAttribute('aria-label', '3D view of the result: ' + text);
    $('view3d-moved-info').textContent = model.moved ? 'boundary moved up to ' + model.moved.max.toPrecision(3) + ' (mesh units, ' +
        (100 * model.moved.max * model.frame.sc / 2 / Math.hypot(...model.frame.half)).toPrecision(2) + '% of the diagonal)' : '';
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

// Mean ratio of every tet. The sign is the file's vertex order; most meshes
// are written positive, and a mesh written all negative is flipped whole
// (qdc orients by the connectivity: the sign most tets have).
function qualities(m) {
    const { nt, xyz, tets } = m;
    const q = new Float32Array(nt);
    let neg = 0;
    for (let t = 0; t < nt; t++) {
        q[t] = meanRatio(xyz, tets[4 * t], tets[4 * t + 1], tets[4 * t + 2], tets[4 * t + 3]);
        if (q[t] < 0) neg++;
    }
    if (neg > nt / 2) for (let t = 0; t < nt; t++) q[t] = -q[t];
    return q;
}

// The six dihedral angles of tet t (degrees): at each edge, the angle between
// the two other vertices seen across it.
function dihedrals(m, t) {
    const P = [0, 1, 2, 3].map((k) => { const v = m.tets[4 * t + k]; return [m.xyz[3 * v], m.xyz[3 * v + 1], m.xyz[3 * v + 2]]; });
    const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const out = [];
    for (const [i, j, k, l] of [[0, 1, 2, 3], [0, 2, 1, 3], [0, 3, 1, 2], [1, 2, 0, 3], [1, 3, 0, 2], [2, 3, 0, 1]]) {
        const e = sub(P[j], P[i]);
        const ee = dot(e, e) || 1;
        const perp = (p) => { const d = sub(p, P[i]); const s = dot(d, e) / ee; return [d[0] - s * e[0], d[1] - s * e[1], d[2] - s * e[2]]; };
        const u = perp(P[k]), v = perp(P[l]);
        const c = dot(u, v) / (Math.sqrt(dot(u, u) * dot(v, v)) || 1);
        out.push((Math.acos(Math.max(-1, Math.min(1, c))) * 180) / Math.PI);
    }
    return out;
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
    return { ctr, sc, half: [0, 1, 2].map((k) => ((mx[k] - mn[k]) / 2) * sc) };
}

// Quality -> colour: inverted magenta, then red (0) through yellow (0.4) to
// green (0.8 and better).
function qcolor(q) {
    if (q <= 0) return [0.8, 0.1, 0.8];
    const t = Math.min(1, q / 0.8);
    return t < 0.5 ? [0.9, 0.15 + 1.4 * t, 0.1] : [0.9 - 1.4 * (t - 0.5), 0.85 - 0.2 * (t - 0.5), 0.1 + 0.4 * (t - 0.5)];
}

// Append triangle a b c of mesh m (flat normal, colour rgb) to out at o.
function putTri(out, o, m, fr, a, b, c, rgb) {
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
        out[o++] = rgb ? rgb[0] : 1; out[o++] = rgb ? rgb[1] : 1; out[o++] = rgb ? rgb[2] : 1;
    }
    return o;
}

// The four faces of each tet of list into a buffer (the tet of each triangle too).
function tetFaces(m, fr, list, color) {
    const buf = new Float32Array(list.length * 4 * 3 * FLOATS);
    const tet = new Int32Array(list.length * 4);
    let o = 0, k = 0;
    for (const t of list) for (const f of FACES) {
        o = putTri(buf, o, m, fr, m.tets[4 * t + f[0]], m.tets[4 * t + f[1]], m.tets[4 * t + f[2]], color ? color(t) : null);
        tet[k++] = t;
    }
    return { buf, tet };
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
    const buf = new Float32Array(surf.length * 3 * FLOATS);
    const tet = new Int32Array(surf.length);
    const vid = new Int32Array(surf.length * 3);
    let o = 0;
    surf.forEach((fidx, k) => {
        const t = fidx >> 2, f = fidx & 3;
        tet[k] = t;
        for (let j = 0; j < 3; j++) vid[3 * k + j] = tets[4 * t + F[f][j]];
        o = putTri(buf, o, m, fr, vid[3 * k], vid[3 * k + 1], vid[3 * k + 2], null);
    });
    return { buf, tet, vid, n: surf.length };
}

// The worst tets by mean ratio (0.2% of them, 10 to 200), as their four faces.
// Candidates below a threshold taken from a 1024-bin histogram, so only a few
// are sorted even on a million tets.
function worstTets(m, q, fr) {
    const nt = m.nt;
    const bins = new Int32Array(1024);
    const bin = (v) => Math.max(0, Math.min(1023, Math.floor((v + 1) * 512)));
    for (let t = 0; t < nt; t++) bins[bin(q[t])]++;
    const n = Math.min(nt, Math.max(10, Math.min(200, Math.ceil(nt * 0.002))));
    let last = 0;
    for (let acc = 0; last < 1024 && (acc += bins[last]) < n; last++);
    const cand = [];
    for (let t = 0; t < nt; t++) if (bin(q[t]) <= last) cand.push(t);
    cand.sort((i, j) => q[i] - q[j]);
    const worst = cand.slice(0, n);
    const { buf, tet } = tetFaces(m, fr, worst, null);
    return { buf, tet, n: worst.length, q: worst.length ? q[worst[worst.length - 1]] : NaN };
}

// The tets of m that the plane n.p = d (normalized frame) cuts, coloured by q.
function cutTets(model, axis, d) {
    const { result: m, frame: fr, q } = model;
    const list = [];
    for (let t = 0; t < m.nt && list.length < MAX_CUT_TETS; t++) {
        let lo = Infinity, hi = -Infinity;
        for (let k = 0; k < 4; k++) {
            const v = (m.xyz[3 * m.tets[4 * t + k] + axis] - fr.ctr[axis]) * fr.sc;
            if (v < lo) lo = v;
            if (v > hi) hi = v;
        }
        if (lo <= d && hi >= d) list.push(t);
    }
    return Object.assign(tetFaces(m, fr, list, (t) => qcolor(q[t])), { n: list.length });
}

// The boundary coloured by how far each vertex moved from its input position
// (blue-grey: not at all, to orange: the most any moved): a copy of the
// surface buffer with its colours set per vertex. The largest distance in
// mesh units too.
function movedColours(surf, model) {
    const { result: m, input: i0 } = model;
    const d = new Float64Array(surf.vid.length);
    let max = 0;
    for (let k = 0; k < surf.vid.length; k++) {
        const v = surf.vid[k];
        d[k] = Math.hypot(m.xyz[3 * v] - i0.xyz[3 * v], m.xyz[3 * v + 1] - i0.xyz[3 * v + 1], m.xyz[3 * v + 2] - i0.xyz[3 * v + 2]);
        if (d[k] > max) max = d[k];
    }
    const buf = surf.buf.slice();
    for (let k = 0; k < d.length; k++) {
        const t = max > 0 ? Math.sqrt(d[k] / max) : 0; // sqrt: small moves still show
        buf[k * FLOATS + 6] = 0.55 + 0.43 * t;
        buf[k * FLOATS + 7] = 0.62 - 0.1 * t;
        buf[k * FLOATS + 8] = 0.75 - 0.65 * t;
    }
    return { buf, max };
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

// p (model) rotated by the column-major rotation r
const rot3 = (r, x, y, z) => [r[0] * x + r[4] * y + r[8] * z, r[1] * x + r[5] * y + r[9] * z, r[2] * x + r[6] * y + r[10] * z];
const rot3t = (r, x, y, z) => [r[0] * x + r[1] * y + r[2] * z, r[4] * x + r[5] * y + r[6] * z, r[8] * x + r[9] * y + r[10] * z];

const FOVY = 0.8;
const HOME = { yaw: 0.6, pitch: 0.4 };

// model: {result, input, frame, q, qin}; layers: [{name, data (Float32Array
// of FLOATS per vertex), tet (the tet of each triangle), color [r,g,b,a],
// vertexColor, blend, clip (cut away by the clip plane), lod (thinned while
// turning), onTop, box (a checkbox that shows/hides it)}]; opaque layers are
// drawn first.
function viewer(canvas, gl, model, layers) {
    const vs = 'attribute vec3 p; attribute vec3 n; attribute vec3 c; uniform mat4 mvp; uniform mat4 rot;' +
        'varying vec3 vn; varying vec3 vc; varying vec3 vp;' +
        'void main() { gl_Position = mvp * vec4(p, 1.0); vn = (rot * vec4(n, 0.0)).xyz; vc = c; vp = p; }';
    const fs = 'precision mediump float; varying vec3 vn; varying vec3 vc; varying vec3 vp;' +
        'uniform vec4 color; uniform float useVc; uniform vec4 plane; uniform float clipOn;' +
        'void main() { if (clipOn > 0.5 && dot(vp, plane.xyz) > plane.w) discard;' +
        ' float l = abs(normalize(vn).z); vec3 base = useVc > 0.5 ? vc : color.rgb;' +
        ' gl_FragColor = vec4(base * (0.35 + 0.65 * l), color.a); }';
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
    const A = { p: gl.getAttribLocation(prog, 'p'), n: gl.getAttribLocation(prog, 'n'), c: gl.getAttribLocation(prog, 'c') };
    const U = {};
    for (const k of ['mvp', 'rot', 'color', 'useVc', 'plane', 'clipOn']) U[k] = gl.getUniformLocation(prog, k);
    const upload = (l, data) => {
        if (!l.b) l.b = gl.createBuffer();
        gl.bindBuffer(gl.ARRAY_BUFFER, l.b);
        gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW);
        l.data = data;
        l.n = data.length / FLOATS;
    };
    const bufs = layers.map((l) => { const b = Object.assign({}, l); upload(b, l.data); return b; });
    const byName = (n) => bufs.find((l) => l.name === n);
    // the thinned boundary: every k-th triangle
    const surf = byName('surface');
    const ntri = surf.n / 3;
    const stride = Math.max(1, Math.ceil(ntri / LOD_TRIS));
    const thinOut = () => {
        if (stride === 1) return;
        const thin = new Float32Array(Math.ceil(ntri / stride) * 3 * FLOATS);
        let o = 0;
        for (let t = 0; t < ntri; t += stride) {
            thin.set(surf.data.subarray(t * 3 * FLOATS, (t + 1) * 3 * FLOATS), o);
            o += 3 * FLOATS;
        }
        if (!surf.lodLayer) surf.lodLayer = {};
        upload(surf.lodLayer, thin.subarray(0, o));
    };
    thinOut();
    // the boundary plain (see-through) or coloured by how far it moved (opaque)
    const plain = surf.data;
    const setMoved = () => {
        const on = $('view3d-moved').checked && model.moved;
        upload(surf, on ? model.moved.buf : plain);
        surf.vertexColor = !!on;
        surf.blend = !on;
        thinOut();
        canvas.dataset.moved = on ? '1' : '0';
        redraw();
    };
    const cam = { yaw: HOME.yaw, pitch: HOME.pitch, dist: 3, target: [0, 0, 0] };
    const clip = { axis: -1, d: 0 };
    let queued = false, stopped = false, dragging = false, frames = 0, firstAt = 0;
    const aspect = () => Math.max(1, canvas.clientWidth) / Math.max(1, canvas.clientHeight);
    const rotNow = () => rotation(cam.yaw, cam.pitch);
    // Fit: the boundary's vertices (every k-th) in view, for this rotation:
    // a point p' (rotated, about the target) fits when |x'| <= (d - z') tan(fov_x / 2).
    const fit = () => {
        const d = surf.data;
        const mn = [Infinity, Infinity, Infinity], mx = [-Infinity, -Infinity, -Infinity];
        const step = FLOATS * Math.max(1, Math.floor(d.length / FLOATS / 200000));
        for (let i = 0; i < d.length; i += step) for (let k = 0; k < 3; k++) {
            if (d[i + k] < mn[k]) mn[k] = d[i + k];
            if (d[i + k] > mx[k]) mx[k] = d[i + k];
        }
        if (!(mx[0] >= mn[0])) return;
        cam.target = [0, 1, 2].map((k) => (mn[k] + mx[k]) / 2);
        const r = rotNow();
        const ty = Math.tan(FOVY / 2), tx = ty * aspect();
        let need = 0.1;
        for (let i = 0; i < d.length; i += step) {
            const v = rot3(r, d[i] - cam.target[0], d[i + 1] - cam.target[1], d[i + 2] - cam.target[2]);
            need = Math.max(need, v[2] + Math.abs(v[0]) / tx, v[2] + Math.abs(v[1]) / ty);
        }
        cam.dist = need * 1.04;
    };
    const bind = (buf) => {
        gl.bindBuffer(gl.ARRAY_BUFFER, buf.b);
        gl.enableVertexAttribArray(A.p);
        gl.vertexAttribPointer(A.p, 3, gl.FLOAT, false, 4 * FLOATS, 0);
        gl.enableVertexAttribArray(A.n);
        gl.vertexAttribPointer(A.n, 3, gl.FLOAT, false, 4 * FLOATS, 12);
        gl.enableVertexAttribArray(A.c);
        gl.vertexAttribPointer(A.c, 3, gl.FLOAT, false, 4 * FLOATS, 24);
    };
    const draw = () => {
        queued = false;
        if (stopped) return;
        const dpr = window.devicePixelRatio || 1;
        // while turning: half the resolution (a quarter of the pixels)
        const scale = dragging ? 0.5 : 1;
        const w = Math.max(1, Math.round(canvas.clientWidth * dpr * scale)), h = Math.max(1, Math.round(canvas.clientHeight * dpr * scale));
        if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
        gl.viewport(0, 0, w, h);
        gl.clearColor(0.063, 0.086, 0.122, 1);
        gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
        const rot = rotNow();
        const t = cam.target;
        const view = mul(mul(new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -cam.dist, 1]), rot),
            new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -t[0], -t[1], -t[2], 1]));
        const mvp = mul(perspective(FOVY, w / h, Math.max(0.01, cam.dist / 100), cam.dist * 10 + 10), view);
        gl.uniformMatrix4fv(U.mvp, false, mvp);
        gl.uniformMatrix4fv(U.rot, false, rot);
        const pl = [0, 0, 0];
        if (clip.axis >= 0) pl[clip.axis] = 1;
        gl.uniform4f(U.plane, pl[0], pl[1], pl[2], clip.d);
        gl.enable(gl.DEPTH_TEST);
        const shown = bufs.filter((l) => l.n && (!l.box || l.box.checked));
        const opaque = shown.some((l) => !l.blend);
        let drawn = 0;
        for (const l0 of shown) {
            const l = dragging && l0.lodLayer ? l0.lodLayer : l0;
            gl.depthMask(!l0.blend);
            if (l0.blend) {
                gl.enable(gl.BLEND);
                gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
            } else {
                gl.disable(gl.BLEND);
            }
            if (l0.onTop) gl.disable(gl.DEPTH_TEST);
            bind(l);
            // alone, the surface is drawn nearly opaque
            gl.uniform4f(U.color, l0.color ? l0.color[0] : 1, l0.color ? l0.color[1] : 1, l0.color ? l0.color[2] : 1,
                l0.vertexColor ? 1 : l0.blend && !opaque && !l0.onTop ? 0.9 : l0.color[3]);
            gl.uniform1f(U.useVc, l0.vertexColor ? 1 : 0);
            gl.uniform1f(U.clipOn, l0.clip && clip.axis >= 0 ? 1 : 0);
            gl.drawArrays(gl.TRIANGLES, 0, l.n);
            drawn += l.n / 3;
            if (l0.onTop) gl.enable(gl.DEPTH_TEST);
        }
        gl.depthMask(true);
        frames++;
        canvas.dataset.frames = String(frames);
        canvas.dataset.lod = dragging ? 'drag: ' + w + 'x' + h + ' px, ' + drawn + ' triangles' : 'full: ' + w + 'x' + h + ' px, ' + drawn + ' triangles';
        canvas.dataset.layers = shown.filter((l) => l.name !== 'picked' && l.name !== 'cut').map((l) => l.name + ':' + l.n / 3).join(' ');
        canvas.dataset.triangles = String(ntri);
        canvas.dataset.camera = [cam.yaw, cam.pitch, cam.dist, ...cam.target].map((v) => v.toFixed(3)).join(' ');
    };
    const redraw = () => { if (!queued) { queued = true; requestAnimationFrame(draw); } };
    // a click: the nearest triangle under the pointer (Moller-Trumbore), of
    // the layers shown, beyond the clip plane's cut away part
    const pick = (cx, cy) => {
        const rect = canvas.getBoundingClientRect();
        const nx = ((cx - rect.left) / rect.width) * 2 - 1, ny = 1 - ((cy - rect.top) / rect.height) * 2;
        const ty = Math.tan(FOVY / 2), tx = ty * aspect();
        const r = rotNow();
        const o = rot3t(r, 0, 0, cam.dist).map((v, k) => v + cam.target[k]);
        const dir = rot3t(r, nx * tx, ny * ty, -1);
        let best = Infinity, bestTet = -1, bestLayer = '';
        for (const l of bufs) {
            if (!l.n || l.name === 'picked' || (l.box && !l.box.checked)) continue;
            const d = l.data;
            for (let i = 0, tri = 0; i < d.length; i += 3 * FLOATS, tri++) {
                const e1x = d[i + FLOATS] - d[i], e1y = d[i + FLOATS + 1] - d[i + 1], e1z = d[i + FLOATS + 2] - d[i + 2];
                const e2x = d[i + 2 * FLOATS] - d[i], e2y = d[i + 2 * FLOATS + 1] - d[i + 1], e2z = d[i + 2 * FLOATS + 2] - d[i + 2];
                const px = dir[1] * e2z - dir[2] * e2y, py = dir[2] * e2x - dir[0] * e2z, pz = dir[0] * e2y - dir[1] * e2x;
                const det = e1x * px + e1y * py + e1z * pz;
                if (Math.abs(det) < 1e-12) continue;
                const inv = 1 / det;
                const sx = o[0] - d[i], sy = o[1] - d[i + 1], sz = o[2] - d[i + 2];
                const u = (sx * px + sy * py + sz * pz) * inv;
                if (u < 0 || u > 1) continue;
                const qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
                const v = (dir[0] * qx + dir[1] * qy + dir[2] * qz) * inv;
                if (v < 0 || u + v > 1) continue;
                const t = (e2x * qx + e2y * qy + e2z * qz) * inv;
                if (t <= 0 || t >= best) continue;
                if (l.clip && clip.axis >= 0 && o[clip.axis] + t * dir[clip.axis] > clip.d) continue;
                best = t;
                bestTet = l.tet[tri];
                bestLayer = l.name;
            }
        }
        return bestTet >= 0 ? { tet: bestTet, layer: bestLayer } : null;
    };
    const showPick = (hit) => {
        const box = $('view3d-pick');
        const picked = byName('picked');
        if (!hit) {
            upload(picked, new Float32Array(0));
            box.textContent = 'Nothing under the pointer: click a boundary triangle or a tet.';
            delete canvas.dataset.picked;
        } else {
            const t = hit.tet;
            upload(picked, tetFaces(model.result, model.frame, [t], null).buf);
            const ang = dihedrals(model.result, t);
            box.textContent = 'Tet ' + t + ' (' + ({ surface: 'on the boundary', cut: 'cut by the plane', before: 'among the input\'s worst', after: 'among the result\'s worst' }[hit.layer]) +
                '): mean ratio ' + sgn(model.q[t], 4) + (model.qin ? ' (input ' + sgn(model.qin[t], 4) + ')' : '') +
                '; dihedral angles ' + ang.map((a) => a.toFixed(1) + '°').join(', ') + ' (smallest ' + Math.min(...ang).toFixed(2) + '°, largest ' + Math.max(...ang).toFixed(2) + '°).';
            canvas.dataset.picked = String(t);
        }
        redraw();
    };
    const setClip = () => {
        const axis = ['x', 'y', 'z'].indexOf($('view3d-clip').value);
        const cut = byName('cut');
        $('view3d-clip-pos').disabled = axis < 0;
        clip.axis = axis;
        if (axis < 0) {
            upload(cut, new Float32Array(0));
            $('view3d-cut-info').textContent = '';
            delete canvas.dataset.cut;
        } else {
            const half = model.frame.half[axis];
            clip.d = (-1 + (2 * +$('view3d-clip-pos').value) / 100) * half * 1.001;
            const c = cutTets(model, axis, clip.d);
            cut.tet = c.tet;
            upload(cut, c.buf);
            $('view3d-cut-info').textContent = int(c.n) + ' tets cut by the plane ' + 'xyz'[axis] + ' = ' +
                (clip.d / model.frame.sc + model.frame.ctr[axis]).toPrecision(4) + (c.n >= MAX_CUT_TETS ? ' (the first ' + int(MAX_CUT_TETS) + ')' : '') +
                ', coloured by mean ratio; the boundary beyond it is cut away.';
            canvas.dataset.cut = String(c.n);
        }
        redraw();
    };
    const ptrs = new Map();
    let pinch = 0, downAt = null;
    canvas.onpointerdown = (e) => {
        canvas.setPointerCapture(e.pointerId);
        ptrs.set(e.pointerId, [e.clientX, e.clientY]);
        downAt = [e.clientX, e.clientY];
    };
    canvas.onpointerup = canvas.onpointercancel = (e) => {
        ptrs.delete(e.pointerId);
        pinch = 0;
        if (!ptrs.size) {
            const click = downAt && e.type === 'pointerup' && Math.hypot(e.clientX - downAt[0], e.clientY - downAt[1]) < 4;
            downAt = null;
            if (dragging) { dragging = false; redraw(); }
            if (click) showPick(pick(e.clientX, e.clientY));
        }
    };
    canvas.onpointermove = (e) => {
        const p = ptrs.get(e.pointerId);
        if (!p) return;
        if (!dragging && downAt && Math.hypot(e.clientX - downAt[0], e.clientY - downAt[1]) >= 4) dragging = true;
        if (!dragging) return;
        if (ptrs.size === 1) {
            cam.yaw += (e.clientX - p[0]) * 0.01;
            cam.pitch = Math.max(-1.55, Math.min(1.55, cam.pitch + (e.clientY - p[1]) * 0.01));
        }
        ptrs.set(e.pointerId, [e.clientX, e.clientY]);
        if (ptrs.size === 2) {
            const [a, b] = [...ptrs.values()];
            const d = Math.hypot(a[0] - b[0], a[1] - b[1]);
            if (pinch) cam.dist = Math.max(0.05, Math.min(50, cam.dist * pinch / d));
            pinch = d;
        }
        redraw();
    };
    canvas.addEventListener('wheel', (e) => {
        e.preventDefault();
        cam.dist = Math.max(0.05, Math.min(50, cam.dist * Math.exp(e.deltaY * 0.001)));
        redraw();
    }, { passive: false });
    // keyboard: arrows turn, + and - zoom, f fits, 0 resets (the canvas takes focus)
    canvas.tabIndex = 0;
    canvas.onkeydown = (e) => {
        const k = e.key;
        if (k === 'ArrowLeft' || k === 'ArrowRight') cam.yaw += k === 'ArrowLeft' ? -0.1 : 0.1;
        else if (k === 'ArrowUp' || k === 'ArrowDown') cam.pitch = Math.max(-1.55, Math.min(1.55, cam.pitch + (k === 'ArrowUp' ? -0.1 : 0.1)));
        else if (k === '+' || k === '=') cam.dist /= 1.1;
        else if (k === '-') cam.dist *= 1.1;
        else if (k === 'f') fit();
        else if (k === '0') { cam.yaw = HOME.yaw; cam.pitch = HOME.pitch; fit(); }
        else return;
        e.preventDefault();
        redraw();
    };
    $('view3d-fit').onclick = () => { fit(); redraw(); };
    $('view3d-reset').onclick = () => { cam.yaw = HOME.yaw; cam.pitch = HOME.pitch; fit(); redraw(); };
    $('view3d-clip').onchange = setClip;
    $('view3d-moved').checked = false;
    $('view3d-moved').disabled = !model.moved;
    $('view3d-moved').onchange = setMoved;
    $('view3d-clip-pos').oninput = setClip;
    $('view3d-clip').value = '';
    $('view3d-clip-pos').value = '50';
    $('view3d-pick').textContent = '';
    $('view3d-cut-info').textContent = '';
    window.addEventListener('resize', redraw);
    for (const l of layers) if (l.box) l.box.onchange = redraw;
    fit();
    // the first frame now (not at the next animation frame), finished, so that
    // its time can be told
    draw();
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
    firstAt = performance.now();
    return {
        stop: () => { stopped = true; window.removeEventListener('resize', redraw); },
        firstFrame: () => firstAt,
    };
}

// --------------------------------------------------------------------- init --

function init() {
    $('token-form').addEventListener('submit', tokenEntered);
    $('token-dialog').addEventListener('cancel', (e) => e.preventDefault());
    $('forget').hidden = !token();
    $('forget').onclick = () => { sessionStorage.removeItem(TOKEN_KEY); location.reload(); };
    $('file').addEventListener('change', (e) => chooseFiles(e.target.files));
    const drop = $('drop');
    drop.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('over'); });
    drop.addEventListener('dragleave', () => drop.classList.remove('over'));
    drop.addEventListener('drop', (e) => {
        e.preventDefault();
        drop.classList.remove('over');
        if (e.dataTransfer.files.length) chooseFiles(e.dataTransfer.files);
    });
    $('submit-form').addEventListener('submit', submit);
    chartHover($('chart'), $('chart-tip'), $('chart-line'), () => {
        const st = hoverState();
        return st ? { geom: st.chartGeom, recs: st.recs } : { recs: [] };
    });
    histHover($('hist'), $('hist-tip'), () => { const st = hoverState(); return st && st.histGeom; });
    listToolsInit();
    $('cmp-hist-log').onchange = () => { if (view && view.redraw) view.redraw(); };
    for (const b of $('filters').querySelectorAll('button')) {
        b.addEventListener('click', () => {
            listState.filter = b.dataset.state;
            for (const o of $('filters').querySelectorAll('button')) {
                o.classList.toggle('on', o === b);
                o.setAttribute('aria-pressed', String(o === b));
            }
            renderJobs();
        });
    }
    route();
}

init();
