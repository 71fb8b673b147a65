// console.mjs - the qdcd web console in a real headless browser (Debian's
// chromium, driven by playwright-core). Run by tests/server/ui.sh, which
// starts qdcd and passes everything through the environment:
//   UI_MODULES   directory holding node_modules/playwright-core (npm ci)
//   QDC_URL      the daemon, e.g. http://127.0.0.1:41417
//   UI_MODE      "open" (no tokens) or "tokens" (UI_TOKEN is valid)
//   UI_OUT       directory for downloads and measurements (figures.json)
//   UI_SHOTS     where the screenshots go (docs/ of the repository), or empty
//   SAMPLE       tests/data/sample/cube.mesh; BIG a gzipped dev mesh (a long
//                literal-mode run: the chart grows); SHOT a gzipped dev mesh
//                submitted with the form untouched (the screenshots)
//   TANGLED      a gzipped tangled dev mesh: with the finishing pass off its
//                run starts again from the input (the chart's rerun notes)
//   OPTIONS_JSON `qdc options` output
//   UI_MODE=big: BIG_ID, BIG_RECORDS name a finished ~1M-tet job: time its view
// Prints "ok - ..." / "FAIL - ..." lines like the shell suites.
import { readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { gunzipSync } from 'node:zlib';
import { view3dPixels, chartChecks, view3dChecks, view3dSpeed, rerunChecks, noColumnCut, ariaChecks, axeChecks } from './views.mjs';
import { chromium, pass, fail, check, failed, until } from './tap.mjs';

const env = process.env;
const URL = env.QDC_URL;
const OUT = env.UI_OUT;
const figures = {};
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

const authH = env.UI_MODE === 'tokens' ? { Authorization: 'Bearer ' + env.UI_TOKEN } : {};
async function apiJSON(p, opts) {
    const res = await fetch(URL + p, Object.assign({ headers: authH }, opts || {}));
    return { status: res.status, body: await res.json().catch(() => null) };
}
const h = { pass, fail, check, apiJSON, figures };

const browser = await chromium.launch({
    executablePath: env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    // root in a container: no user namespaces for the sandbox; SwiftShader
    // gives headless chromium a WebGL (software) for the 3D view
    args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'],
});
const context = await browser.newContext({ viewport: { width: 1280, height: 900 }, acceptDownloads: true });
const page = await context.newPage();
const errors = [];
const expected = []; // [from, to, regex]: errors[from..to) the test provoked
// jobs that are gone on purpose (deleted, or never were): a 404 of their URLs
// is the test's doing whenever it comes (a poll may land after the step)
const gone = [];
page.on('console', (m) => {
    if (m.type() === 'error') errors.push(m.text() + (m.location().url ? ' <' + m.location().url + '>' : ''));
});
page.on('pageerror', (e) => errors.push('page error: ' + e.message));
await page.addInitScript(() => {
    window.__draws = [];
    document.addEventListener('qdc:chart', (e) => window.__draws.push({ t: Date.now(), seq: e.detail.seq, points: e.detail.points }));
});

async function firstPaint(pg, where) {
    await pg.goto(URL + (where || '/'), { waitUntil: 'load' });
    // first-contentful-paint, from the start of the navigation (buffered: it
    // may have happened before this script runs)
    return pg.evaluate(() => new Promise((resolve) => {
        const nav = performance.getEntriesByType('navigation')[0];
        const done = (e) => resolve({ fcp: e ? e.startTime : null, load: nav ? nav.loadEventEnd : null });
        new PerformanceObserver((l) => {
            const e = l.getEntries().find((x) => x.name === 'first-contentful-paint');
            if (e) done(e);
        }).observe({ type: 'paint', buffered: true });
        setTimeout(() => done(null), 5000);
    }));
}

async function submitFile(file, opts) {
    await page.setInputFiles('#file', file);
    for (const [k, v] of Object.entries(opts || {})) {
        const sel = '#opts [name="' + k + '"]';
        if (typeof v === 'boolean') await page.setChecked(sel, v);
        else if ((await page.$eval(sel, (e) => e.tagName)) === 'SELECT') await page.selectOption(sel, v);
        else await page.fill(sel, String(v));
    }
    await page.click('#submit-btn');
    await page.waitForURL(/\/ui\/jobs\/[0-9a-f]{32}$/, { timeout: 60000 });
    return page.url().split('/').pop();
}

async function waitDone(id, ms) {
    await until(async () => (await apiJSON('/v1/jobs/' + id)).body.done, ms, 'job ' + id + ' to end');
    await page.waitForSelector('#report-card:not([hidden])', { timeout: 15000 });
    await page.waitForFunction(() => +document.getElementById('hist').dataset.drawn > 0, null, { timeout: 5000 });
}

async function download(format, file) {
    const [dl] = await Promise.all([page.waitForEvent('download'), page.click('#downloads a[data-format="' + format + '"]')]);
    await dl.saveAs(path.join(OUT, file));
    return dl.suggestedFilename();
}

try {
    if (env.UI_MODE === 'big') {
        // ---------------------------------------- a finished ~1M-tet job --
        const n = +env.BIG_RECORDS;
        const job = (await apiJSON('/v1/jobs/' + env.BIG_ID)).body;
        figures.big_tets = job.mesh.tets;
        figures.big_view_ms = [];
        for (let k = 0; k < 3; k++) {
            const t0 = Date.now();
            await page.goto(URL + '/ui/jobs/' + env.BIG_ID);
            await page.waitForFunction((m) => +document.getElementById('chart').dataset.points === m &&
                +document.getElementById('hist').dataset.drawn > 0 && document.querySelectorAll('#threshold-table tbody tr').length === 8 &&
                document.querySelectorAll('#downloads a').length > 10, n, { timeout: 20000 });
            figures.big_view_ms.push(Date.now() - t0);
        }
        check(Math.max(...figures.big_view_ms) <= 2000, 'finished ' + job.mesh.tets + '-tet job: the view opens with its ' + n +
            ' records charted, histograms, threshold counts and downloads in ' + figures.big_view_ms.join(', ') + ' ms (target 2 s)',
            JSON.stringify(figures.big_view_ms));
        const auto = await page.evaluate(() => !document.getElementById('view3d-load').hidden);
        const t1 = Date.now();
        await page.click('#view3d-load');
        const layers = await page.waitForFunction(() => {
            const c = document.getElementById('view3d');
            const s = document.getElementById('view3d-status').textContent;
            return /after:/.test(c.dataset.layers || '') ? c.dataset.layers : /not available/.test(s) ? 'none' : null;
        }, null, { timeout: 60000 }).then((h) => h.jsonValue());
        figures.big_3d_ms = Date.now() - t1;
        figures.big_3d_status = await page.textContent('#view3d-status');
        if (layers === 'none') console.log('ok - 1M-tet 3D view # SKIP no WebGL in this chromium');
        else check(auto && /before:\d+/.test(layers), '1M-tet job: the 3D view waits for its button, then shows the boundary and the worst tets before and after in ' +
            figures.big_3d_ms + ' ms (' + layers + ')', layers);
    } else if (env.UI_MODE === 'tokens') {
        // ------------------------------------------------------ with tokens --
        await page.goto(URL + '/');
        await page.waitForSelector('#token-dialog[open]', { timeout: 5000 });
        pass('tokens: the page asks for a token when /v1 answers 401');
        await page.fill('#token-input', 'not-the-token');
        await page.click('#token-form button[type=submit]');
        await page.waitForFunction(() => document.getElementById('token-dialog').open &&
            !document.getElementById('token-error').hidden, null, { timeout: 5000 });
        pass('tokens: a wrong token is refused and asked again');
        await page.fill('#token-input', env.UI_TOKEN);
        await page.click('#token-form button[type=submit]');
        await page.waitForFunction(() => /No jobs yet/.test(document.getElementById('jobs-empty').textContent), null, { timeout: 5000 });
        const store = await page.evaluate(() => ({ s: sessionStorage.getItem('qdc.token'), l: localStorage.length, c: document.cookie }));
        check(store.s === env.UI_TOKEN && store.l === 0 && store.c === '',
            'tokens: the token is kept in sessionStorage only (no localStorage, no cookie)', JSON.stringify(store));
        const id = await submitFile(env.SAMPLE);
        await waitDone(id, 60000);
        const job = (await apiJSON('/v1/jobs/' + id)).body;
        check(job && job.state === 'succeeded', 'tokens: the sample submitted through the page succeeded (job visible to this token)', JSON.stringify(job && job.state));
        const other = await fetch(URL + '/v1/jobs/' + id);
        check(other.status === 401, 'tokens: the same job without the token is 401', other.status);
        const name = await download('medit', 'tok.mesh');
        pass('tokens: result downloaded with the token (fetch + blob), as ' + name);
        // a reload in the same tab keeps the token; a new tab asks again
        await page.reload();
        await page.waitForSelector('#view-job:not([hidden]) #report-card:not([hidden])', { timeout: 10000 });
        const asked = await page.evaluate(() => document.getElementById('token-dialog').open);
        check(!asked, 'tokens: a reload of the tab keeps the token', 'dialog open');
        const p2 = await context.newPage();
        await p2.goto(URL + '/');
        await p2.waitForSelector('#token-dialog[open]', { timeout: 5000 });
        pass('tokens: another tab (its own session storage) asks again');
        await p2.close();
    } else {
        // ---------------------------------------------------------- no tokens --
        // First paint, in a chromium of its own with default flags (SwiftShader
        // GL, which the 3D view needs here, slows the compositor's start). The
        // browser's own start (a renderer for this origin) is not the page's:
        // in each of five fresh contexts (empty caches), open a same-origin
        // URL first, then /livez once more (the baseline: a 16-byte JSON
        // document from the same daemon, which chromium paints as text), then
        // / with the empty cache, then once more revalidated. What is
        // measured is mostly chromium's own pipeline, which a busy machine
        // slows for both pages alike: the medians of / are judged against the
        // baseline's median (at most FP_RATIO times it; 2.6-3.2 measured with
        // two busy loops beside other work, load about 20 on 2 cores); 300 ms,
        // the target on an idle 2-core machine (medians of 210-230 ms there),
        // is printed.
        // (the console's own page, which polls and draws, is parked on a blank
        // page meanwhile: on 2 cores it competed with the measured one)
        // A round whose medians miss is taken again, up to three rounds: a
        // spell of load can fall on one page and not the other; a page that
        // is slow misses in every round.
        const FP_RATIO = 5;
        await page.goto('about:blank');
        const fpb = await chromium.launch({ executablePath: env.CHROMIUM || '/usr/bin/chromium', args: ['--no-sandbox'] });
        const median = (a) => (a.some((x) => x === null) ? null : [...a].sort((x, y) => x - y)[a.length >> 1]);
        const ms = (a) => a.map((x) => (x === null ? 'none' : x.toFixed(0))).join(', ');
        const rounds = [];
        let cold, warm, base, mc, mw, mb;
        const fpOk = () => mc !== null && mw !== null && mb !== null && mc <= FP_RATIO * mb && mw <= FP_RATIO * mb;
        for (let round = 0; round < 3; round++) {
            cold = [];
            warm = [];
            base = [];
            for (let i = 0; i < 5; i++) {
                const ctx = await fpb.newContext();
                const fpp = await ctx.newPage();
                await fpp.goto(URL + '/livez');
                base.push((await firstPaint(fpp, '/livez')).fcp);
                cold.push((await firstPaint(fpp)).fcp);
                warm.push((await firstPaint(fpp)).fcp);
                await ctx.close();
            }
            mc = median(cold);
            mw = median(warm);
            mb = median(base);
            rounds.push({ baseline: base, empty_cache: cold, revalidated: warm });
            if (fpOk()) break;
        }
        await fpb.close();
        await page.goto(URL + '/');
        figures.first_paint_ms = rounds;
        const m0 = (x) => (x === null ? 'none' : x.toFixed(0));
        check(fpOk(), 'first paint of /: median ' + m0(mc) + ' ms with an empty cache (' + ms(cold) + '), ' + m0(mw) +
            ' ms revalidated by ETag (' + ms(warm) + '); at most ' + FP_RATIO + ' x the median first paint of /livez, ' + m0(mb) +
            ' ms (' + ms(base) + ') (target on an idle machine: 300 ms)' +
            (rounds.length > 1 ? ' (round ' + rounds.length + '; before: ' + rounds.slice(0, -1).map((r) => 'median ' + ms([median(r.empty_cache)]) + '/' +
                ms([median(r.revalidated)]) + ' vs ' + ms([median(r.baseline)])).join(', ') + ')' : ''),
            JSON.stringify(figures.first_paint_ms));
        await page.waitForFunction(() => /No jobs yet/.test(document.getElementById('jobs-empty').textContent), null, { timeout: 5000 });
        pass('/ loads without a token: empty job list');

        // the form's defaults are the library's (qdc options), read from /v1/options
        await page.waitForSelector('#opts [data-default]', { timeout: 5000 });
        const table = JSON.parse(readFileSync(env.OPTIONS_JSON, 'utf8'));
        const form = await page.$$eval('#opts [data-default]', (es) => es.map((e) => [e.name, e.dataset.default,
            e.type === 'checkbox' ? (e.checked ? 'on' : 'off') : e.value]));
        const bad = [];
        let compared = 0;
        for (const [name, def, shown] of form) {
            if (def !== shown) bad.push(name + ': shows ' + shown + ', default ' + def);
            const o = table.find((t) => t.name === name);
            if (!o) { if (name !== 'tetgen_quality') bad.push(name + ': not an option'); continue; }
            compared++;
            if (o.type === 'integer' || o.type === 'number' ? +o.default !== +def : o.default !== def)
                bad.push(name + ': form ' + def + ', qdc options ' + o.default);
        }
        const shownDefs = Object.fromEntries(form.map(([n, d]) => [n, d]));
        check(!bad.length && compared >= 8, 'submit form: ' + compared + ' options with the defaults of `qdc options` shown (boundary ' +
            shownDefs.boundary + ', hausd ' + shownDefs.hausd + ', stall ' + shownDefs.stall + ')', bad.join('; '));

        // drag and drop picks the file; a surface enables the TetGen option
        const tq = () => page.$eval('#opts [name="tetgen_quality"]', (e) => e.disabled);
        const tqBefore = await tq();
        const dt = await page.evaluateHandle(() => {
            const d = new DataTransfer();
            d.items.add(new File(['solid s\nendsolid s\n'], 'part.stl', { type: 'model/stl' }));
            return d;
        });
        await page.dispatchEvent('#drop', 'dragover', { dataTransfer: dt });
        await page.dispatchEvent('#drop', 'drop', { dataTransfer: dt });
        const info = await page.textContent('#file-info');
        check(tqBefore && !(await tq()) && /part\.stl/.test(info) && /surface/.test(info),
            'drag and drop: the dropped part.stl is chosen as a surface, tetgen_quality enabled (' + info + ')', info);
        // a bad file: the daemon's problem, with its line, shown under the form
        await page.setInputFiles('#file', { name: 'bad.mesh', mimeType: 'text/plain',
            buffer: Buffer.from('MeshVersionFormatted 2\nDimension 3\nVertices\n2\n0 0 0 0\n1 nan 0 0\nEnd\n') });
        check(await tq(), 'a .mesh file disables the surface-only option', 'enabled');
        const e400 = errors.length;
        await page.click('#submit-btn');
        await page.waitForSelector('#submit-error:not([hidden])', { timeout: 10000 });
        expected.push([e400, errors.length, /status of 400/]);
        const perr = await page.textContent('#submit-error');
        check(/\(400\)/.test(perr) && /line 6/.test(perr) && /view-list/.test(await page.evaluate(() =>
            document.getElementById('view-list').hidden ? 'view-job' : 'view-list')),
            'a malformed upload: the page shows the problem (' + perr.split('\n')[0].slice(0, 70) + '…, line 6) and stays', perr);

        // the sample through the file input
        const t0 = Date.now();
        const id1 = await submitFile(env.SAMPLE);
        pass('sample submitted through the file input, job view at /ui/jobs/' + id1 + ' (' + (Date.now() - t0) + ' ms)');
        await waitDone(id1, 60000);
        const prog = (await apiJSON('/v1/jobs/' + id1 + '/progress?after=-1')).body;
        await page.waitForFunction((n) => +document.getElementById('chart').dataset.points === n, prog.count, { timeout: 5000 })
            .then(() => pass('chart: all ' + prog.count + ' progress records drawn from /events'))
            .catch(() => fail('chart points', 'want ' + prog.count));
        const rows = await page.$$eval('#threshold-table tbody tr', (t) => t.length);
        const q = await page.$$eval('#quality-table tbody tr', (t) => t.map((r) => r.textContent));
        const rep = (await apiJSON('/v1/jobs/' + id1 + '/report')).body;
        check(rows === 8 && q[0].includes(rep.after.mean_ratio_mean.toFixed(4)) && q[0].includes(rep.before.mean_ratio_mean.toFixed(4)),
            'report: histograms drawn, 8 threshold rows, mean ratio ' + rep.before.mean_ratio_mean.toFixed(4) + ' -> ' +
            rep.after.mean_ratio_mean.toFixed(4) + ' as in /report', rows + ' ' + q[0]);
        // downloads: every format the daemon offers (its 400 lists them)
        const offered = (await apiJSON('/v1/jobs/' + id1 + '/result?format=none')).body.formats;
        const links = await page.$$eval('#downloads a', (as) => as.map((a) => a.dataset.format));
        const missing = offered.filter((f) => !links.includes(f));
        check(offered.length >= 10 && !missing.length, 'downloads: a link per offered format (' + offered.join(' ') + ') and the report',
            'missing ' + missing.join(' '));
        // the upload's own format is marked: that file is the upload written back
        const own = (await apiJSON('/v1/jobs/' + id1)).body.mesh.format;
        const marked = await page.$$eval('#downloads a', (as) => as.filter((a) => /as uploaded/.test(a.textContent)).map((a) => a.dataset.format));
        check(marked.length === 1 && marked[0] === own, 'downloads: the upload\'s own format (' + own + ') is the one marked "as uploaded"',
            JSON.stringify(marked));
        const name = await download('medit', 'sample-out.mesh');
        const qname = await download('qmesh', 'sample-out.qmesh');
        // the job keeps the upload's file name: title, header, download names
        const j1 = (await apiJSON('/v1/jobs/' + id1)).body;
        const title = await page.title();
        const shownName = await page.textContent('#job-name');
        const stem = path.basename(env.SAMPLE).replace(/\.[^.]*$/, '');
        check(j1.file_name === path.basename(env.SAMPLE) && title.includes(j1.file_name) && shownName === j1.file_name &&
            name === stem + '.qdc.mesh' && qname === stem + '.qdc.qmesh',
        'names: the page sends the file\'s name (' + j1.file_name + '): page title "' + title + '", downloads ' + name + ' and ' + qname,
        JSON.stringify({ file_name: j1.file_name, title, shownName, name, qname }));
        const tri = await page.waitForFunction(() => {
            const c = document.getElementById('view3d');
            const s = document.getElementById('view3d-status').textContent;
            return +c.dataset.triangles > 0 ? 'webgl:' + c.dataset.triangles : /WebGL/.test(s) && /not available/.test(s) ? 'none' : null;
        }, null, { timeout: 15000 }).then((h) => h.jsonValue()).catch((e) => 'error ' + e.message);
        if (tri === 'none') console.log('ok - 3D view # SKIP no WebGL in this chromium (the page says so and works without it)');
        else check(tri.startsWith('webgl:'), '3D view: ' + tri.slice(6) + ' boundary triangles drawn (WebGL)', tri);
        if (tri.startsWith('webgl:')) {
            // a cube's boundary: 6 faces; this sample's boundary is 2 x 6 x 6 x 6... compare with the mesh
            figures.sample_boundary_triangles = +tri.slice(6);
        }

        // XDMF whose heavy data is in HDF5: the .xdmf alone is not sent (the
        // page asks for its .h5); picked together, both go as FormData
        await page.click('a[data-nav][href="/"]');
        await page.waitForSelector('#view-list:not([hidden])');
        if (env.XDMF_H5) {
            const h5f = env.XDMF_H5.replace(/\.xdmf$/, '.h5');
            const nJobs = (await apiJSON('/v1/jobs?page_size=1000')).body.jobs.length;
            await page.setInputFiles('#file', env.XDMF_H5);
            await page.waitForSelector('#submit-error:not([hidden])', { timeout: 5000 });
            const askH5 = await page.textContent('#submit-error');
            check(/meshio_h5\.h5/.test(askH5) && /together/.test(askH5) && await page.isDisabled('#submit-btn') &&
                (await apiJSON('/v1/jobs?page_size=1000')).body.jobs.length === nJobs,
                'XDMF+HDF5: the .xdmf alone is not sent, the page asks for its .h5 (' + askH5 + ')', askH5);
            const idx = await submitFile([env.XDMF_H5, h5f], { max_iter: 5 });
            await waitDone(idx, 60000);
            const jx = (await apiJSON('/v1/jobs/' + idx)).body;
            const rx = await fetch(URL + '/v1/jobs/' + idx + '/result?format=h5', { headers: authH });
            check(jx.state === 'succeeded' && jx.mesh.tets === 1228 && jx.file_name === 'meshio_h5.xdmf' && rx.status === 200,
                'XDMF+HDF5: meshio_h5.xdmf and meshio_h5.h5 picked together, sent as FormData: job succeeded (' +
                jx.mesh.tets + ' tets), its result?format=h5 there', JSON.stringify([jx.state, jx.mesh, jx.file_name, rx.status]));
            // the job's .h5 among the downloads, as result.h5 (the name its .xdmf gives it)
            await page.waitForSelector('#downloads a[data-format="h5"]', { timeout: 10000 }).catch(() => {});
            const h5name = await page.$('#downloads a[data-format="h5"]') ? await download('h5', 'xdmf-result.h5') : 'none';
            const h5got = h5name === 'none' ? Buffer.alloc(0) : readFileSync(path.join(OUT, 'xdmf-result.h5'));
            check(h5name === 'result.h5' && h5got.subarray(0, 8).equals(Buffer.from([0x89, 0x48, 0x44, 0x46, 0x0d, 0x0a, 0x1a, 0x0a])),
                'XDMF+HDF5: the job page offers its .h5 as result.h5 (an HDF5 file of ' + h5got.length + ' bytes)', h5name);
            // the pair gzipped (.xmf.gz + .h5.gz): gunzipped by the page, sent as the pair
            await page.click('a[data-nav][href="/"]');
            await page.waitForSelector('#view-list:not([hidden])');
            const gzd = path.join(path.dirname(env.XDMF_H5), '..', 'xh5gz');
            const idz = await submitFile([path.join(gzd, 'meshio_h5.xmf.gz'), path.join(gzd, 'meshio_h5.h5.gz')],
                { max_iter: 5 });
            await waitDone(idz, 60000);
            const jz = (await apiJSON('/v1/jobs/' + idz)).body;
            await page.waitForSelector('#downloads a[data-format="h5"]', { timeout: 10000 }).catch(() => {});
            check(jz.state === 'succeeded' && jz.mesh.tets === 1228 && jz.mesh.h5 === true &&
                jz.file_name === 'meshio_h5.xmf' && !!(await page.$('#downloads a[data-format="h5"]')),
                'XDMF+HDF5 gzipped: meshio_h5.xmf.gz and meshio_h5.h5.gz gunzipped by the page and sent as the pair (' +
                jz.mesh.tets + ' tets, mesh.h5 ' + jz.mesh.h5 + ', its .h5 offered)', JSON.stringify([jz.state, jz.mesh, jz.file_name]));
            // deleted: the checks below count the jobs of this run (the page,
            // still on idz's view, may ask for its input after: 404s of its own)
            gone.push(idx, idz);
            const del = await fetch(URL + '/v1/jobs/' + idx, { method: 'DELETE', headers: authH });
            const delz = await fetch(URL + '/v1/jobs/' + idz, { method: 'DELETE', headers: authH });
            check(del.status === 204 && delz.status === 204 &&
                (await apiJSON('/v1/jobs?page_size=1000')).body.jobs.length === nJobs,
                'XDMF+HDF5: the jobs deleted again', String(del.status) + ' ' + delz.status);
            await page.click('a[data-nav][href="/"]');
        } else {
            console.log('ok - XDMF+HDF5 upload # SKIP qdc-h5 not built');
        }

        // a longer run (literal mode: no early stop): the chart grows while it runs
        await page.waitForSelector('#view-list:not([hidden])');
        await page.waitForFunction((id) => !!document.querySelector('#jobs tr[data-id="' + id + '"]'), id1, { timeout: 5000 });
        const polled = {};
        let polling = true;
        let pollId = null;
        const poller = (async () => {
            while (polling && !pollId) await sleep(5);
            let after = -1;
            while (polling) {
                const b = (await apiJSON('/v1/jobs/' + pollId + '/progress?after=' + after + '&wait=20')).body;
                const t = Date.now();
                for (const r of b.records) polled[r.seq] = t;
                after = b.next_after;
                if (b.done) break;
            }
        })();
        // find the new job's id as soon as it exists, for the long-poll
        const watchNew = (async () => {
            while (!pollId && polling) {
                const l = (await apiJSON('/v1/jobs')).body.jobs;
                const j = l.find((x) => x.id !== id1);
                if (j) pollId = j.id;
                else await sleep(5);
            }
        })();
        // upload at 4 MB/s (DevTools network emulation) to see the progress bar move
        const cdp = await context.newCDPSession(page);
        await cdp.send('Network.emulateNetworkConditions', { offline: false, latency: 0,
            downloadThroughput: -1, uploadThroughput: 4e6 });
        await page.evaluate(() => {
            window.__bar = [];
            const bar = document.getElementById('upload-progress');
            const t = setInterval(() => { if (!bar.hidden) window.__bar.push(bar.value); }, 20);
            window.__barStop = () => clearInterval(t);
        });
        await page.fill('#label-input', 'big, literal mode');
        const id2 = await submitFile(env.BIG, { max_iter: 60, mode: 'literal' });
        await cdp.send('Network.emulateNetworkConditions', { offline: false, latency: 0, downloadThroughput: -1, uploadThroughput: -1 });
        const bar = await page.evaluate(() => { window.__barStop(); return window.__bar; });
        const lab2 = (await apiJSON('/v1/jobs/' + id2)).body.label;
        check(lab2 === 'big, literal mode', 'label: the upload form\'s label is the job\'s (' + lab2 + ')', lab2);
        const mid = bar.filter((v) => v > 0.05 && v < 0.95);
        check(mid.length >= 2 && bar[bar.length - 1] >= mid[mid.length - 1], 'upload progress bar moves (' + mid.length +
            ' readings between 5% and 95% at 4 MB/s)', JSON.stringify(bar.slice(0, 20)));
        await watchNew;
        // the baseline for the chart's latency: round trips of /livez from the
        // page itself while the job runs (its event loop and qdcd, as busy as
        // they are for the chart)
        await page.evaluate(() => {
            window.__rtt = [];
            let on = true;
            (async () => {
                while (on) {
                    const t = performance.now();
                    await fetch('/livez', { cache: 'no-store' }).then((r) => r.text()).catch(() => {});
                    window.__rtt.push(performance.now() - t);
                    await new Promise((r) => setTimeout(r, 100));
                }
            })();
            window.__rttStop = () => { on = false; return window.__rtt; };
        });
        const seen = [];
        const tRun = Date.now();
        for (;;) {
            const s = await page.evaluate(() => [document.getElementById('job-state').textContent,
                +document.getElementById('chart').dataset.points]);
            if (s[0] === 'running' && (!seen.length || seen[seen.length - 1] !== s[1])) seen.push(s[1]);
            if (/succeeded|failed|cancelled/.test(s[0]) || Date.now() - tRun > 120000) break;
            await sleep(30);
        }
        check(seen.length >= 3 && seen.every((v, i) => !i || v > seen[i - 1]), 'chart gains points while the job runs: ' +
            seen.length + ' distinct counts seen in state running (' + seen.slice(0, 6).join(', ') + (seen.length > 6 ? ', … ' + seen[seen.length - 1] : '') + ')',
            JSON.stringify(seen));
        const rtt = (await page.evaluate(() => (window.__rttStop ? window.__rttStop() : []))).sort((a, b) => a - b);
        await waitDone(id2, 120000);
        polling = false;
        await poller;
        // chart latency: when the page drew a record vs when a long-poll got it
        const draws = await page.evaluate(() => window.__draws);
        const firstDraw = draws.find((d) => d.points > 0);
        const lat = [];
        for (const [seq, t] of Object.entries(polled)) {
            if (!firstDraw || t < firstDraw.t) continue; // delivered before the stream was open
            const d = draws.find((x) => x.seq >= +seq && x.t >= t - 1000);
            if (d) lat.push(d.t - t);
        }
        lat.sort((a, b) => a - b);
        figures.chart_latency_ms = { n: lat.length, median: lat[lat.length >> 1], p90: lat[Math.floor(lat.length * 0.9)], max: lat[lat.length - 1] };
        // at most 10 x the p90 of the page's /livez round trips, and never
        // less than 250 ms (the target on an idle machine: a round trip of a
        // millisecond there says nothing of the page's scheduling)
        const rttP90 = rtt.length ? rtt[Math.floor(rtt.length * 0.9)] : 0;
        const latLim = Math.max(250, 10 * rttP90);
        figures.chart_latency_ms.livez_rtt_p90 = Math.round(rttP90);
        check(lat.length >= 10 && figures.chart_latency_ms.p90 <= latLim, 'chart latency (drawn after a long-poll got the record): median ' +
            figures.chart_latency_ms.median + ' ms, p90 ' + figures.chart_latency_ms.p90 + ' ms, max ' + figures.chart_latency_ms.max +
            ' ms over ' + lat.length + ' records; limit ' + Math.round(latLim) + ' ms = 10 x the page\'s /livez p90 ' + rttP90.toFixed(0) + ' ms over ' +
            rtt.length + ' round trips, floor 250 ms (the target on an idle machine)', JSON.stringify(figures.chart_latency_ms));
        const j2 = (await apiJSON('/v1/jobs/' + id2)).body;
        check(j2.state === 'succeeded' && j2.mesh.tets > 100000, 'gzipped ' + path.basename(env.BIG) + ' gunzipped by the page and optimized (' +
            j2.mesh.tets + ' tets, ' + j2.iterations + ' iterations)', JSON.stringify(j2.state));
        await download('medit', 'big-out.mesh');
        // the 3D view of the 100k-tet result
        await page.waitForFunction(() => +document.getElementById('view3d').dataset.triangles > 0 ||
            /not available/.test(document.getElementById('view3d-status').textContent), null, { timeout: 30000 }).catch(() => {});
        // the job view of a finished job opens (a reload: page, job, all records,
        // report), against the same view of the sample's job (750 tets, a few
        // records) opened the same way: the best of three of each, alternated.
        // The target on an idle machine, 2 s, is printed.
        const VIEW_RATIO = 6;
        const openView = async (id, j) => {
            await page.goto(URL + '/ui/jobs/' + id);
            await page.waitForFunction(() => +document.getElementById('view3d').dataset.triangles > 0 ||
                /not available/.test(document.getElementById('view3d-status').textContent), null, { timeout: 30000 }).catch(() => {});
            const t = Date.now();
            await page.reload();
            await page.waitForFunction((n) => +document.getElementById('chart').dataset.points === n &&
                +document.getElementById('hist').dataset.drawn > 0, j.iterations + 1, { timeout: 60000 }); // records 0..iterations
            return Date.now() - t;
        };
        const jSmall = (await apiJSON('/v1/jobs/' + id1)).body;
        const vBig = [], vSmall = [];
        for (let i = 0; i < 3; i++) {
            vSmall.push(await openView(id1, jSmall));
            vBig.push(await openView(id2, j2));
        }
        figures.finished_job_view_ms = Math.min(...vBig);
        figures.small_job_view_ms = Math.min(...vSmall);
        check(figures.finished_job_view_ms <= VIEW_RATIO * figures.small_job_view_ms, 'finished ' + j2.mesh.tets +
            '-tet job view opens with chart and histograms in ' + figures.finished_job_view_ms + ' ms (' + vBig.join(', ') + '), at most ' +
            VIEW_RATIO + ' x the ' + jSmall.mesh.tets + '-tet job\'s ' + figures.small_job_view_ms + ' ms (' + vSmall.join(', ') +
            ') (target on an idle machine: 2 s)', JSON.stringify({ big: vBig, small: vSmall }));
        await page.waitForFunction(() => +document.getElementById('view3d').dataset.triangles > 0 ||
            /not available/.test(document.getElementById('view3d-status').textContent), null, { timeout: 30000 }).catch(() => {});
        figures.view3d_status = await page.textContent('#view3d-status');
        // the 3D view of the 100k-tet result: first frame, frames per second
        // turning (lighter detail) and at rest, in software rendering
        figures.view3d_100k = await view3dSpeed(page, h);
        if (figures.view3d_100k) {
            const v = figures.view3d_100k;
            check(v.first_frame_ms > 0 && v.fps_turning > 0 && v.fps_full_detail > 0, '3D view of ' + j2.mesh.tets + ' tets (' + v.boundary_triangles +
                ' boundary triangles), software rendering: first frame ' + v.first_frame_ms + ' ms after the request, ' + v.fps_turning +
                ' frames/s turning (lighter detail), ' + v.fps_full_detail + ' frames/s turning by keys at full detail', JSON.stringify(v));
        }

        // the screenshot job: a mesh with inverted tets, the form untouched
        await page.click('a[data-nav][href="/"]');
        await page.waitForSelector('#view-list:not([hidden])');
        const id4 = await submitFile(env.SHOT);
        await waitDone(id4, 120000);
        const j4 = (await apiJSON('/v1/jobs/' + id4)).body;
        const odiff = table.filter((o) => o.name !== 'time_limit').filter((o) => {
            const v = j4.options[o.name];
            return o.type === 'bool' ? v !== (o.default === 'on') : o.type === 'integer' || o.type === 'number' ? v !== +o.default : v !== o.default;
        }).map((o) => o.name + ' ' + j4.options[o.name] + ' (default ' + o.default + ')');
        check(j4.state === 'succeeded' && !odiff.length, path.basename(env.SHOT) + ' submitted with the form untouched: the job ran with the defaults of `qdc options` (boundary ' +
            j4.options.boundary + ', hausd ' + j4.options.hausd + ', stall ' + j4.options.stall + ')', j4.state + ' ' + odiff.join('; '));
        const r4 = (await apiJSON('/v1/jobs/' + id4 + '/progress?after=-1')).body.records;
        await page.waitForFunction((n) => +document.getElementById('chart').dataset.points === n, r4.length, { timeout: 5000 }).catch(() => {});
        const [f4, l4] = [r4[0], r4[r4.length - 1]];
        figures.shot_run = { records: r4.length, phases: [...new Set(r4.map((r) => r.phase))].join(' '),
            mean: [f4.mean_ratio_mean, l4.mean_ratio_mean], worst: [f4.mean_ratio_min, l4.mean_ratio_min], inverted: [f4.n_inverted, l4.n_inverted] };
        check(+(await page.getAttribute('#chart', 'data-points')) === r4.length && f4.n_inverted > 0 && l4.n_inverted === 0 &&
            l4.mean_ratio_min > f4.mean_ratio_min && l4.mean_ratio_mean > f4.mean_ratio_mean,
            'chart of the default run: ' + r4.length + ' records (' + figures.shot_run.phases + '), worst mean ratio ' + f4.mean_ratio_min.toFixed(3) +
            ' -> ' + l4.mean_ratio_min.toFixed(3) + ', mean ' + f4.mean_ratio_mean.toFixed(3) + ' -> ' + l4.mean_ratio_mean.toFixed(3) +
            ', inverted ' + f4.n_inverted + ' -> 0', JSON.stringify(figures.shot_run));
        // the 3D view: the input's worst tets (orange) and the result's (red),
        // counted in the canvas's pixels, each set hidden by its checkbox
        const layers = await page.waitForFunction(() => {
            const c = document.getElementById('view3d');
            const s = document.getElementById('view3d-status').textContent;
            return /after:/.test(c.dataset.layers || '') ? c.dataset.layers : /not available/.test(s) ? 'none' : null;
        }, null, { timeout: 30000 }).then((h) => h.jsonValue()).catch((e) => 'error ' + e.message);
        if (layers === 'none') {
            console.log('ok - 3D view of the worst tets before and after # SKIP no WebGL in this chromium');
        } else {
            const px = () => view3dPixels(page);
            const both = await px();
            await page.click('#view3d-before');
            const noBefore = await px();
            await page.click('#view3d-after');
            const none = await px();
            await page.click('#view3d-before');
            await page.click('#view3d-after');
            const again = await px();
            figures.view3d_pixels = { both, noBefore, none, again };
            const nb = /before:(\d+)/.exec(both.layers), na = /after:(\d+)/.exec(both.layers);
            check(nb && na && +nb[1] > 0 && +na[1] > 0 && both.orange > 100 && both.red > 100 && noBefore.orange === 0 && noBefore.red > 100 &&
                none.orange === 0 && none.red === 0 && again.orange > 100 && again.red > 100,
                '3D view: the input\'s ' + (+nb[1] / 4) + ' worst tets drawn in orange (' + both.orange + ' px) and the result\'s ' + (+na[1] / 4) +
                ' in red (' + both.red + ' px); unchecking "before" leaves ' + noBefore.orange + ' orange px, both unchecked ' + (none.orange + none.red) + ' px',
                JSON.stringify(figures.view3d_pixels));
        }
        figures.shot_view3d_status = await page.textContent('#view3d-status');
        const o4 = (await apiJSON('/v1/jobs/' + id4 + '/report')).body.outcome;
        const shown4 = await page.evaluate(() => [document.getElementById('outcome-summary').textContent,
            document.getElementById('outcome-warning').hidden]);
        check(o4 && shown4[0] === 'Outcome: ' + o4.summary && shown4[1] === !o4.warnings.length,
            'outcome: the job page shows the report\'s outcome (' + (o4 && o4.warnings.length ? 'warned' : 'no warning') + ')', JSON.stringify(shown4));
        await chartChecks(page, id4, h);
        await view3dChecks(page, id4, h, URL, authH);
        await ariaChecks(page, h);
        await page.evaluate(() => document.getElementById('hist-log').click());
        await page.waitForFunction(() => document.getElementById('hist').dataset.log === '1', null, { timeout: 10000 }).catch(() => {});
        if (env.UI_SHOTS) await page.screenshot({ path: path.join(env.UI_SHOTS, 'ui-job.png'), fullPage: true });

        // a run that starts again from the input: the chart says where and why
        const idR = (await (await fetch(URL + '/v1/jobs?format=medit&finish=off', { method: 'POST',
            body: gunzipSync(readFileSync(env.TANGLED)) })).json()).id;
        await until(async () => (await apiJSON('/v1/jobs/' + idR)).body.done, 120000, 'the rerun job');
        await page.goto(URL + '/ui/jobs/' + idR);
        await page.waitForFunction(() => +document.getElementById('hist').dataset.drawn > 0, null, { timeout: 10000 });
        await rerunChecks(page, idR, h);
        // the outcome in words: the report's summary, and its warnings and
        // suggestions in an alert (16 tets left inverted: much is left bad)
        const oR = (await apiJSON('/v1/jobs/' + idR + '/report')).body.outcome;
        await page.waitForSelector('#job-outcome:not([hidden])', { timeout: 10000 }).catch(() => {});
        const shownR = await page.evaluate(() => ({ summary: document.getElementById('outcome-summary').textContent,
            warn: document.getElementById('outcome-warning').hidden ? '' : document.getElementById('outcome-warning').textContent,
            role: document.getElementById('outcome-warning').getAttribute('role') }));
        check(oR && oR.warnings.length > 0 && shownR.summary === 'Outcome: ' + oR.summary && shownR.role === 'alert' &&
            oR.warnings.every((w) => shownR.warn.includes(w)) && oR.suggestions.length > 0 &&
            oR.suggestions.every((t) => shownR.warn.includes('Suggestion: ' + t)),
            'outcome: a bad result\'s page shows the report\'s summary and, in an alert, its ' + (oR ? oR.warnings.length : 0) +
            ' warnings and suggestions ("' + (oR ? oR.warnings[0] : '') + '")', JSON.stringify(shownR).slice(0, 300));
        if (env.UI_SHOTS) await page.screenshot({ path: path.join(env.UI_SHOTS, 'ui-rerun.png'), fullPage: true });
        // the list shows the result's mean ratio (the report's after), not the last record's
        const repR = (await apiJSON('/v1/jobs/' + idR + '/report')).body;
        const lastR = (await apiJSON('/v1/jobs/' + idR)).body.progress;
        await page.click('a[data-nav][href="/"]');
        const cellR = await page.waitForFunction((id) => {
            const td = document.querySelector('#jobs tr[data-id="' + id + '"] td:nth-child(6)');
            return td && /^\d/.test(td.textContent.trim()) && !/→ –/.test(td.textContent) && td.textContent;
        }, idR, { timeout: 10000 }).then((x) => x.jsonValue()).catch(() => '');
        check(cellR.trim() === repR.before.mean_ratio_mean.toFixed(4) + ' → ' + repR.after.mean_ratio_mean.toFixed(4),
            'list: a job whose last record is not its result shows the report\'s figures (' + cellR.trim() + '; last record ' +
            lastR.mean_ratio_mean.toFixed(4) + ')', cellR);
        await apiJSON('/v1/jobs/' + idR, { method: 'DELETE' });
        await page.goto(URL + '/ui/jobs/' + id4);
        await page.waitForFunction(() => +document.getElementById('hist').dataset.drawn > 0, null, { timeout: 10000 });

        // the list: filter, cancel, delete
        const id3 = (await (await fetch(URL + '/v1/jobs?max_iter=2000&mode=literal&format=medit', { method: 'POST',
            body: readFileSync(path.join(OUT, 'big-out.mesh')) })).json()).id;
        await page.click('a[data-nav][href="/"]');
        const rowSel = (id) => '#jobs tr[data-id="' + id + '"]';
        await page.waitForSelector(rowSel(id3));
        await page.waitForSelector(rowSel(id3) + '[data-state="running"]', { timeout: 15000 })
            .then(() => pass('list: a job submitted by another client shows up, running, within the polling interval'))
            .catch((e) => fail('list running', e.message));
        await noColumnCut(page, 'desktop (1280 px), job list with file names', h);
        const listName = await page.textContent(rowSel(id1) + ' td:first-child a');
        check(listName === path.basename(env.SAMPLE), 'names: the list shows the job by its file\'s name (' + listName + ')', listName);
        // the figures come from the job's report, fetched after the row is drawn
        const inout = await page.waitForFunction((sel) => {
            const td = document.querySelector(sel);
            return td && /^0\.\d{4} → 0\.\d{4}$/.test(td.textContent.trim()) && td.textContent;
        }, rowSel(id2) + ' td:nth-child(6)', { timeout: 10000 }).then((x) => x.jsonValue())
            .catch(() => page.textContent(rowSel(id2) + ' td:nth-child(6)'));
        check(/^0\.\d{4} → 0\.\d{4}$/.test(inout.trim()), 'list: mean ratio in → out shown (' + inout.trim() + ')', inout);
        await page.click('#filters button[data-state="succeeded"]');
        const states = await page.$$eval('#jobs tbody tr', (t) => t.map((r) => r.dataset.state));
        check(states.length === 3 && states.every((s) => s === 'succeeded'), 'list: the succeeded filter shows the 3 succeeded jobs only', states.join(' '));
        await page.click('#filters button[data-state=""]');
        await page.click(rowSel(id3) + ' button[data-act="cancel"]');
        await page.waitForSelector(rowSel(id3) + '[data-state="cancelled"]', { timeout: 15000 })
            .then(() => pass('list: Cancel stops the running job (cancelled)'))
            .catch((e) => fail('cancel', e.message));
        // cancel keeps the best mesh so far: the cancelled job's page offers it, and it downloads
        await page.click(rowSel(id3) + ' td:first-child a');
        const resLink = await page.waitForSelector('#downloads a[data-format="medit"]', { timeout: 15000 })
            .then((a) => a.getAttribute('href')).catch(() => null);
        const got = resLink ? await fetch(URL + resLink, { headers: authH }) : null;
        const body = got && got.status === 200 ? await got.text() : '';
        check(resLink !== null && /^\s*MeshVersionFormatted/.test(body) && /Tetrahedra/.test(body),
            'cancel: the cancelled job\'s page offers its best mesh so far, and it downloads (' +
            (got ? got.status : 'no link') + ', ' + body.length + ' bytes)', resLink + ' ' + (got && got.status));
        await page.click('a[data-nav][href="/"]');
        await page.waitForSelector(rowSel(id3));
        await page.waitForFunction(() => document.querySelectorAll('#jobs tbody tr').length === 4 &&
            [...document.querySelectorAll('#jobs tbody td:nth-child(6)')].filter((t) => /→ 0\./.test(t.textContent)).length >= 3, null, { timeout: 5000 }).catch(() => {});
        if (env.UI_SHOTS) await page.screenshot({ path: path.join(env.UI_SHOTS, 'ui-list.png') });
        // Delete asks first: "Keep it" keeps the job, "Delete" deletes it
        await page.click(rowSel(id3) + ' button[data-act="delete"]');
        const asked = await page.waitForSelector('#confirm-dialog[open]', { timeout: 3000 }).then(() => page.textContent('#confirm-text')).catch(() => '');
        await page.click('#confirm-dialog button[value="cancel"]');
        // the dialog's close is what the page acts on (a delete only on "ok")
        await page.waitForFunction(() => !document.getElementById('confirm-dialog').open, null, { timeout: 5000 }).catch(() => {});
        const kept = (await apiJSON('/v1/jobs/' + id3)).status;
        check(asked.includes(id3.slice(0, 8)) && kept === 200 && (await page.$(rowSel(id3))) !== null,
            'list: Delete asks first ("' + asked.slice(0, 60) + '…"); "Keep it" keeps the job', asked + ' ' + kept);
        await page.click(rowSel(id3) + ' button[data-act="delete"]');
        await page.waitForSelector('#confirm-dialog[open]', { timeout: 3000 });
        await page.click('#confirm-dialog button[value="ok"]');
        await page.waitForSelector(rowSel(id3), { state: 'detached', timeout: 10000 })
            .then(() => pass('list: Delete removes the job'))
            .catch((e) => fail('delete', e.message));
        gone.push(id3);
        const gone3 = await apiJSON('/v1/jobs/' + id3);
        check(gone3.status === 404, 'deleted job: GET /v1/jobs/{id} is 404', gone3.status);

        // a phone: no horizontal overflow, chart and histograms drawn
        await page.setViewportSize({ width: 390, height: 844 });
        await page.goto(URL + '/ui/jobs/' + id4);
        await page.waitForFunction(() => +document.getElementById('hist').dataset.drawn > 0, null, { timeout: 10000 });
        const ov = await page.evaluate(() => [document.documentElement.scrollWidth, window.innerWidth,
            [...document.querySelectorAll('body *')].filter((e) => e.getBoundingClientRect().right > window.innerWidth + 0.5)
                .slice(0, 3).map((e) => e.tagName + '#' + e.id + '.' + e.className)]);
        check(ov[0] <= ov[1], 'phone (390 px): the job view has no horizontal overflow', ov.join(' > '));
        await noColumnCut(page, 'phone (390 px), job view', h);
        if (env.UI_SHOTS) await page.screenshot({ path: path.join(env.UI_SHOTS, 'ui-phone.png') });
        await page.goto(URL + '/');
        await page.waitForSelector('#jobs tbody tr');
        const ov2 = await page.evaluate(() => [document.documentElement.scrollWidth, window.innerWidth]);
        check(ov2[0] <= ov2[1], 'phone (390 px): the list has no horizontal overflow', ov2.join(' > '));
        await noColumnCut(page, 'phone (390 px), job list', h);
        const head = await page.evaluate(() => {
            const card = document.getElementById('jobs-card').getBoundingClientRect();
            return [...document.querySelectorAll('#jobs-card h2, #filters button')].filter((e) => {
                const r = e.getBoundingClientRect();
                return r.right > card.right + 0.5 || r.left < card.left - 0.5;
            }).map((e) => e.textContent);
        });
        check(!head.length, 'phone (390 px): the list\'s header (title and filters) inside its card', head.join(', '));
        await axeChecks(browser, URL, [
            ['job list', '/', 1280, () => document.querySelectorAll('#jobs tbody tr').length > 0],
            ['job list', '/', 390, () => document.querySelectorAll('#jobs tbody tr').length > 0],
            ['job view', '/ui/jobs/' + id4, 1280, () => +document.getElementById('hist').dataset.drawn > 0 && +document.getElementById('view3d').dataset.frames > 0],
            ['job view', '/ui/jobs/' + id4, 390, () => +document.getElementById('hist').dataset.drawn > 0],
        ], env.UI_MODULES, h);
        // a browser without WebGL: the job view works, the 3D card says why it is empty
        const ctx2 = await browser.newContext({ viewport: { width: 1280, height: 900 } });
        const nogl = await ctx2.newPage();
        const noglErrors = [];
        nogl.on('pageerror', (e) => noglErrors.push(e.message));
        nogl.on('console', (m) => { if (m.type() === 'error') noglErrors.push(m.text()); });
        await nogl.addInitScript(() => {
            const get = HTMLCanvasElement.prototype.getContext;
            HTMLCanvasElement.prototype.getContext = function (kind, ...a) {
                return /webgl/.test(kind) ? null : get.call(this, kind, ...a);
            };
        });
        await nogl.goto(URL + '/ui/jobs/' + id4);
        const noglState = await nogl.waitForFunction(() => /WebGL/.test(document.getElementById('view3d-status').textContent) &&
            +document.getElementById('hist').dataset.drawn > 0 && +document.getElementById('chart').dataset.points > 0 &&
            document.getElementById('view3d').hidden ? document.getElementById('view3d-status').textContent : null, null, { timeout: 10000 })
            .then((h) => h.jsonValue()).catch((e) => 'timeout: ' + e.message);
        check(/not available/.test(noglState) && !noglErrors.length, 'without WebGL: chart, histograms and report shown, the 3D card says "' +
            noglState.slice(0, 60) + '…", no errors', noglState + ' ' + noglErrors.join(' | '));
        await ctx2.close();
        // an unknown job (its 404s are the page's business: not counted below)
        const e404 = errors.length;
        gone.push('0'.repeat(32));
        await page.goto(URL + '/ui/jobs/' + '0'.repeat(32));
        await page.waitForFunction(() => /no job/i.test(document.getElementById('job-meta').textContent), null, { timeout: 5000 })
            .then(() => pass('an unknown job id: the job view says there is no such job'))
            .catch((e) => fail('unknown job', e.message));
        expected.push([e404, errors.length, /status of 404/]);
        figures.ids = { sample: id1, big: id2, shot: id4 };
    }
    // expected: the 401s that make the page ask for a token, the resource
    // errors of the steps that provoke them (a bad upload, an unknown job)
    const real = errors.filter((e, i) => !(env.UI_MODE === 'tokens' && /status of 401/.test(e)) &&
        !expected.some(([a, b, re]) => i >= a && i < b && re.test(e)) &&
        !(/status of 404/.test(e) && gone.some((id) => e.includes('/' + id))));
    check(!real.length, 'no console errors (' + env.UI_MODE + ')', real.join(' | '));
} catch (e) {
    fail('browser run (' + env.UI_MODE + ')', e.stack || e);
} finally {
    writeFileSync(path.join(OUT, 'figures-' + env.UI_MODE + '.json'), JSON.stringify(figures, null, 1));
    await browser.close();
}
process.exit(failed());
