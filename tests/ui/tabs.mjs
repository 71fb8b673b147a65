// tabs.mjs - the qdcd web console with several jobs and several tabs, in
// headless chromium (playwright-core). Run by tests/server/uitabs.sh, which
// starts qdcd and passes: UI_MODULES (node_modules), QDC_URL, UI_OUT (a
// directory: figures, and the kill-now / restarted files the shell and this
// script meet at), CHROMIUM, SAMPLE (the sample cube), LONG (a mesh whose
// literal-mode run lasts), SPHERE (a small curved mesh: its boundary moves).
// UI_MODE=big with BIG_ID and SMALL_ID (finished jobs, a big one and a small
// one): only the figures of the big job's page (printed, not judged).
// Prints "ok - ..." / "FAIL - ..." lines like the shell suites.
import { readFileSync, writeFileSync, existsSync } from 'node:fs';
import path from 'node:path';
import os from 'node:os';
import { noColumnCut, axeChecks, view3dSpeed } from './views.mjs';
import { chromium, pass, fail, check, failed, until } from './tap.mjs';

const env = process.env;
const URL = env.QDC_URL;
const OUT = env.UI_OUT;
const figures = {};
const h = { pass, fail, check, figures };

async function api(p, opts) {
    const res = await fetch(URL + p, opts);
    return { status: res.status, body: await res.json().catch(() => null) };
}

// POST a mesh file; the job's id
async function submit(file, query) {
    const r = await api('/v1/jobs?' + query, { method: 'POST', body: readFileSync(file), headers: { 'Content-Type': 'model/x-medit' } });
    if (r.status !== 202) throw new Error('submit ' + query + ': ' + r.status + ' ' + JSON.stringify(r.body));
    return r.body.id;
}

const done = (id) => until(async () => (await api('/v1/jobs/' + id)).body.done, 60000, 'job ' + id + ' to end');

const browser = await chromium.launch({
    executablePath: env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'],
});
const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
const errors = [];
const watch = (p, tag) => {
    p.on('console', (m) => { if (m.type() === 'error') errors.push(tag + ': ' + m.text()); });
    p.on('pageerror', (e) => errors.push(tag + ': page error: ' + e.message));
    return p;
};
const page = watch(await context.newPage(), 'list tab');
const rowIds = () => page.$$eval('#jobs tbody tr', (t) => t.map((r) => r.dataset.id));
const rowSel = (id) => '#jobs tr[data-id="' + id + '"]';
const sortOf = (key) => page.$eval('#jobs th[data-sort="' + key + '"]', (th) => th.getAttribute('aria-sort'));

// A page's first contentful paint, the summary shown (the header's sizes and
// the stats' figures) and the report drawn, in ms from its navigation's start
// (looked at every frame).
async function pageTimes(p, url) {
    await p.goto(URL + url, { waitUntil: 'load' });
    const fcp = await p.evaluate(() => new Promise((resolve) => {
        new PerformanceObserver((l) => {
            const e = l.getEntries().find((x) => x.name === 'first-contentful-paint');
            if (e) resolve(Math.round(e.startTime));
        }).observe({ type: 'paint', buffered: true });
        setTimeout(() => resolve(null), 5000);
    }));
    if (url === '/livez') return { fcp };
    const at = (fn) => p.waitForFunction(fn, null, { timeout: 60000, polling: 'raf' }).then((x) => x.jsonValue()).then(Math.round);
    const summary = await at(() => document.querySelectorAll('#job-stats .stat').length > 1 &&
        / tets/.test(document.getElementById('job-meta').textContent) && performance.now());
    const report = await at(() => +document.getElementById('hist').dataset.drawn > 0 &&
        document.querySelectorAll('#quality-table tbody tr').length > 0 && performance.now());
    // when each request of the page was first answered
    const got = await p.evaluate(() => Object.fromEntries(performance.getEntriesByType('resource').reverse()
        .map((e) => [e.name.replace(/^https?:\/\/[^/]+/, '').replace(/[0-9a-f]{32}/, '{id}'), Math.round(e.responseEnd)])));
    return { fcp, summary, report, got };
}

async function bigFigures() {
    // A finished big job's page (BIG_ID) and, in the same fresh context (an
    // empty cache) just before it, the two baselines that show what the
    // machine's load does to chromium: /livez (a 16-byte document) and a
    // finished small job's page (SMALL_ID). Then the big job's 3D view: its
    // first frame and frame rates, still and while turning.
    const job = (await api('/v1/jobs/' + env.BIG_ID)).body;
    figures.big_tets = job.mesh.tets;
    const runs = [];
    for (let k = 0; k < 3; k++) {
        const ctx = await browser.newContext({ viewport: { width: 1280, height: 900 } });
        const p = await ctx.newPage();
        const livez = await pageTimes(p, '/livez');
        const small = await pageTimes(p, '/ui/jobs/' + env.SMALL_ID);
        const big = await pageTimes(p, '/ui/jobs/' + env.BIG_ID);
        runs.push({ livez_fcp: livez.fcp, small, big });
        if (k === 2) {
            await p.click('#view3d-load');
            figures.big_3d = await view3dSpeed(p, h);
            figures.big_3d_status = await p.textContent('#view3d-status');
        }
        await ctx.close();
    }
    figures.big_runs = runs;
    figures.loadavg = os.loadavg().map((x) => +x.toFixed(1));
    const col = (f) => runs.map(f).join(', ');
    check(runs.every((r) => r.big.fcp !== null && r.small.fcp !== null), 'big job (' + job.mesh.tets + ' tets), ms from navigation: first paint ' +
        col((r) => r.big.fcp) + ' (small job ' + col((r) => r.small.fcp) + ', /livez ' + col((r) => r.livez_fcp) + '); summary ' + col((r) => r.big.summary) +
        ' (small ' + col((r) => r.small.summary) + '); report drawn ' + col((r) => r.big.report) + ' (small ' + col((r) => r.small.report) + '); 3D: ' +
        JSON.stringify(figures.big_3d) + ' (load average ' + figures.loadavg.join(' ') + ')', JSON.stringify(runs));
}

try {
    if (env.UI_MODE === 'big') {
        await bigFigures();
    } else {
        // four jobs of known names: zeta (the sample cube, 3 iterations),
        // alpha and Mid (a sphere, the boundary fixed and the defaults: they
        // are compared), one long run cancelled while two tabs look at it
        const j1 = await submit(env.SAMPLE, 'name=zeta.mesh&label=zeta%20run&max_iter=3');
        const j2 = await submit(env.SPHERE, 'name=alpha.mesh&boundary=fixed');
        const j3 = await submit(env.SPHERE, 'name=Mid.mesh');
        for (const id of [j1, j2, j3]) await done(id);
        const j4 = await submit(env.LONG, 'name=long.mesh&max_iter=2000&mode=literal&finish=0&tol_move=0');

        // ------------------------------------------- state changes, two tabs --
        const tab2 = watch(await context.newPage(), 'job tab');
        await tab2.goto(URL + '/ui/jobs/' + j4);
        await page.goto(URL + '/');
        await page.waitForSelector(rowSel(j4) + '[data-state="running"]', { timeout: 20000 });
        await tab2.waitForFunction(() => document.getElementById('job-state').textContent === 'running', null, { timeout: 20000 });
        const c = await api('/v1/jobs/' + j4 + ':cancel', { method: 'POST' });
        const t0 = Date.now();
        const seen = await Promise.all([
            page.waitForSelector(rowSel(j4) + '[data-state="cancelled"]', { timeout: 15000 }).then(() => Date.now() - t0),
            tab2.waitForFunction(() => document.getElementById('job-state').textContent === 'cancelled', null, { timeout: 15000 }).then(() => Date.now() - t0),
        ]).catch((e) => e.message);
        check(c.status < 300 && Array.isArray(seen), 'a cancel by curl shows without reload in the list tab and the job\'s tab (after ' +
            seen + ' ms)', c.status + ' ' + seen);
        figures.cancel_seen_ms = seen;

        // ---------------------------------------------------- find, filter, sort --
        await page.waitForFunction(() => document.querySelectorAll('#jobs tbody tr').length === 4, null, { timeout: 10000 });
        const byDate = await rowIds();
        check(byDate.join() === [j4, j3, j2, j1].join() && (await sortOf('created')) === 'descending',
            'list: newest first by default (submitted: aria-sort descending)', byDate.join(' '));
        await page.click('#jobs th[data-sort="name"] button');
        const byName = await rowIds();
        check(byName.join() === [j2, j4, j3, j1].join() && (await sortOf('name')) === 'ascending' && (await sortOf('created')) === null,
            'list: the job header sorts by name, A to Z, case aside (alpha, long, Mid, zeta run); aria-sort ascending', byName.join(' '));
        await page.focus('#jobs th[data-sort="name"] button');
        await page.keyboard.press('Enter');
        const byNameDesc = await rowIds();
        check(byNameDesc.join() === [j1, j3, j4, j2].join() && (await sortOf('name')) === 'descending',
            'list: Enter on the focused header turns the order (Z to A; aria-sort descending)', byNameDesc.join(' '));
        await page.focus('#jobs th[data-sort="state"] button');
        await page.keyboard.press('Space');
        const byState = await rowIds();
        check(byState.join() === [j4, j3, j2, j1].join() && (await sortOf('state')) === 'ascending',
            'list: Space on the state header sorts by state (cancelled, then the succeeded newest first)', byState.join(' '));
        await page.selectOption('#jobs-sort', 'created:asc');
        const byDateAsc = await rowIds();
        check(byDateAsc.join() === [j1, j2, j3, j4].join() && (await sortOf('created')) === 'ascending',
            'list: the sort menu, date oldest first', byDateAsc.join(' '));
        await page.fill('#jobs-find', 'ALP');
        const found = await rowIds();
        const count = await page.textContent('#jobs-count');
        check(found.join() === j2 && count === '1 of 4 jobs', 'list: find "ALP" shows alpha.mesh only ("' + count + '")', found.join(' ') + ' ' + count);
        await page.fill('#jobs-find', 'zeta.mesh');
        const byFile = await rowIds();
        check(byFile.join() === j1, 'list: find matches the file name behind a label (zeta.mesh, shown as "zeta run")', byFile.join(' '));
        await page.fill('#jobs-find', j3.slice(0, 10));
        check((await rowIds()).join() === j3, 'list: find matches an id', (await rowIds()).join(' '));
        await page.fill('#jobs-find', 'mesh');
        await page.click('#filters button[data-state="succeeded"]');
        const both = await rowIds();
        const pressed = await page.$eval('#filters button[data-state="succeeded"]', (b) => b.getAttribute('aria-pressed'));
        check(both.join() === [j1, j2, j3].join() && pressed === 'true', 'list: state filter and find together (succeeded, "mesh": 3 jobs, aria-pressed)', both.join(' '));
        await page.fill('#jobs-find', 'nothing-like-this');
        const empty = await page.textContent('#jobs-empty');
        check(/No succeeded jobs matching "nothing-like-this"/.test(empty), 'list: nothing found is said ("' + empty + '")', empty);
        await page.fill('#jobs-find', '');
        await page.click('#filters button[data-state=""]');
        await page.selectOption('#jobs-sort', 'created:desc');

        // ----------------------------------------------------------- a phone --
        await page.setViewportSize({ width: 390, height: 844 });
        await page.waitForSelector(rowSel(j1));
        await page.selectOption('#jobs-sort', 'name:asc');
        const phoneOrder = await rowIds();
        const ov = await page.evaluate(() => {
            const card = document.getElementById('jobs-card').getBoundingClientRect();
            return [document.documentElement.scrollWidth, window.innerWidth,
                [...document.querySelectorAll('#list-tools > *, #list-tools input, #list-tools select')].filter((e) => {
                    const r = e.getBoundingClientRect();
                    return r.width && (r.right > card.right + 0.5 || r.left < card.left - 0.5);
                }).map((e) => e.id || e.tagName)];
        });
        check(phoneOrder.join() === [j2, j4, j3, j1].join() && ov[0] <= ov[1] && !ov[2].length,
            'phone (390 px): the sort menu sorts (the headers are for screen readers there); find, sort and compare inside the card',
            phoneOrder.join(' ') + ' ' + JSON.stringify(ov));
        await noColumnCut(page, 'phone (390 px), list with find and sort', h);
        await page.setViewportSize({ width: 1280, height: 900 });
        await page.selectOption('#jobs-sort', 'created:desc');

        // ------------------------------------------------------------ compare --
        await page.check('input[data-tick="' + j1 + '"]');
        await page.check('input[data-tick="' + j2 + '"]');
        await page.check('input[data-tick="' + j3 + '"]');
        const ticked = await page.$$eval('input.tick', (t) => t.filter((x) => x.checked).map((x) => x.dataset.tick));
        const enabled = await page.$eval('#compare-btn', (b) => !b.disabled);
        check(ticked.sort().join() === [j2, j3].sort().join() && enabled, 'list: a third tick drops the first; Compare is enabled with two', ticked.join(' '));
        await page.click('#compare-btn');
        await page.waitForURL(URL + '/#compare/' + j2 + '/' + j3, { timeout: 5000 });
        await page.waitForFunction(() => +document.getElementById('cmp-hist-a').dataset.drawn > 0 && +document.getElementById('cmp-hist-b').dataset.drawn > 0 &&
            document.querySelectorAll('#cmp-quality tbody tr').length > 0, null, { timeout: 10000 });
        const ra = (await api('/v1/jobs/' + j2 + '/report')).body;
        const rb = (await api('/v1/jobs/' + j3 + '/report')).body;
        const cmp = await page.evaluate(() => {
            const row = (t, label) => [...document.querySelectorAll('#' + t + ' tbody tr')].find((r) => r.querySelector('th').textContent === label);
            // a cell's value (the first text; a note or a second line follows)
            const first = (n) => (n.nodeType === 3 ? n.textContent : first(n.firstChild));
            const cells = (t, label) => [...row(t, label).querySelectorAll('td')].map(first);
            return {
                differ: document.getElementById('cmp-options').dataset.differ,
                diffRows: [...document.querySelectorAll('#cmp-options tr.diff th')].map((x) => x.textContent),
                diffNote: document.querySelector('#cmp-options tr.diff td .vh') ? document.querySelector('#cmp-options tr.diff td .vh').textContent : '',
                mean: cells('cmp-quality', 'mean ratio: mean'),
                small: cells('cmp-quality', 'smallest dihedral'),
                haus: cells('cmp-boundary', 'Hausdorff'),
                input: document.getElementById('cmp-input').textContent,
                heads: [...document.querySelectorAll('#cmp-quality thead th')].map((x) => x.textContent + ':' + x.getAttribute('scope')),
                alt: [document.getElementById('cmp-hist-a').getAttribute('aria-label'), document.getElementById('cmp-hist-b').getAttribute('aria-label')],
            };
        });
        check(cmp.differ === 'boundary' && cmp.diffRows.join() === 'boundary' && /differs/.test(cmp.diffNote),
            'compare: the one option that differs (boundary: fixed vs slide) is marked, in colour and in words', JSON.stringify(cmp));
        const f4 = (x) => x.toFixed(4);
        check(cmp.mean.join() === [ra.before, ra.after, rb.before, rb.after].map((x) => f4(x.mean_ratio_mean)).join() &&
            cmp.small.join() === [ra.before, ra.after, rb.before, rb.after].map((x) => x.dihedral_min.toFixed(2) + '°').join(),
        'compare: both quality tables, before and after, as the two reports (mean ratio ' + cmp.mean.join(' / ') + ')', JSON.stringify(cmp));
        check(cmp.haus.join() === [ra, rb].map((r) => r.boundary_error.hausdorff.toPrecision(4)).join() && ra.boundary_error.hausdorff < rb.boundary_error.hausdorff,
            'compare: the boundary moved, both (Hausdorff ' + cmp.haus.join(' vs ') + ': fixed moves it less than slide)', JSON.stringify(cmp.haus));
        check(/^Same input/.test(cmp.input) && cmp.heads.includes('A:colgroup') && cmp.heads.includes('after:col') &&
            cmp.alt.every((a) => /^Job [AB]\. Histogram of all dihedral angles/.test(a)),
        'compare: same input said; column headers with scope; both histograms with a text alternative', JSON.stringify(cmp));
        await noColumnCut(page, 'desktop (1280 px), compare', h);
        await page.setViewportSize({ width: 390, height: 844 });
        await page.waitForTimeout(100);
        await noColumnCut(page, 'phone (390 px), compare', h);
        const ovc = await page.evaluate(() => [document.documentElement.scrollWidth, window.innerWidth]);
        check(ovc[0] <= ovc[1], 'phone (390 px): the compare view has no horizontal overflow', ovc.join(' > '));
        await page.setViewportSize({ width: 1280, height: 900 });
        await axeChecks(browser, URL, [
            ['list with find, sort and ticks', '/', 1280, () => document.querySelectorAll('#jobs tbody tr').length > 0],
            ['list with find, sort and ticks', '/', 390, () => document.querySelectorAll('#jobs tbody tr').length > 0],
            ['compare', '/#compare/' + j2 + '/' + j3, 1280, () => +document.getElementById('cmp-hist-b').dataset.drawn > 0],
            ['compare', '/#compare/' + j2 + '/' + j3, 390, () => +document.getElementById('cmp-hist-b').dataset.drawn > 0],
        ], env.UI_MODULES, h);

        // ---------------------------------------- deletions seen by every tab --
        // a curl DELETE: the job's tab says so, the list tab drops the row, a
        // compare view naming it says so
        const tab3 = watch(await context.newPage(), 'compare tab');
        await tab3.goto(URL + '/#compare/' + j1 + '/' + j3);
        await tab3.waitForFunction(() => +document.getElementById('cmp-hist-b').dataset.drawn > 0, null, { timeout: 10000 });
        await tab2.goto(URL + '/ui/jobs/' + j1);
        await tab2.waitForSelector('#report-card:not([hidden])', { timeout: 10000 });
        await page.goto(URL + '/');
        await page.waitForSelector(rowSel(j1));
        const del = await api('/v1/jobs/' + j1, { method: 'DELETE' });
        const t1 = Date.now();
        const seenDel = await Promise.all([
            tab2.waitForSelector('#job-follow[data-kind="deleted"]:not([hidden])', { timeout: 15000 }).then(() => Date.now() - t1),
            page.waitForSelector(rowSel(j1), { state: 'detached', timeout: 15000 }).then(() => Date.now() - t1),
            tab3.waitForFunction(() => /Job A \(zeta run\) was deleted/.test(document.getElementById('cmp-status').textContent), null, { timeout: 15000 }).then(() => Date.now() - t1),
        ]).catch((e) => e.message);
        const gone = await tab2.evaluate(() => [document.getElementById('job-follow').textContent, document.getElementById('job-state').textContent,
            document.getElementById('downloads-card').hidden, document.getElementById('job-delete').hidden, document.getElementById('job-follow').getAttribute('role')]);
        check(del.status === 204 && Array.isArray(seenDel) && /was deleted/.test(gone[0]) && gone[1] === 'deleted' && gone[2] && gone[3] && gone[4] === 'status',
            'a DELETE by curl: the job\'s tab says "' + gone[0].slice(0, 50) + '…" (a status region; downloads gone), the list tab drops it, ' +
            'the compare tab says so (after ' + seenDel + ' ms)', del.status + ' ' + seenDel + ' ' + JSON.stringify(gone));
        figures.curl_delete_seen_ms = seenDel;
        // a delete in another tab of the page: told at once (BroadcastChannel)
        await tab2.goto(URL + '/ui/jobs/' + j4);
        await tab2.waitForFunction(() => document.getElementById('job-state').textContent === 'cancelled', null, { timeout: 10000 });
        await page.click(rowSel(j4) + ' button[data-act="delete"]');
        await page.waitForSelector('#confirm-dialog[open]', { timeout: 3000 });
        const t2 = Date.now();
        const delDone = page.waitForResponse((r) => r.request().method() === 'DELETE').then(() => Date.now() - t2);
        await page.click('#confirm-dialog button[value="ok"]');
        const seenTab = await tab2.waitForSelector('#job-follow[data-kind="deleted"]:not([hidden])', { timeout: 15000 })
            .then(() => Date.now() - t2).catch((e) => e.message);
        figures.tab_delete_answered_ms = await delDone;
        check(typeof seenTab === 'number', 'a Delete in the list tab: the job\'s tab says it was deleted (after ' + seenTab + ' ms; the DELETE answered after ' +
            figures.tab_delete_answered_ms + ' ms)', seenTab);
        figures.tab_delete_seen_ms = seenTab;
        await tab3.close();

        // ------------------------------------------ a restart (kill -9 qdcd) --
        const j5 = await submit(env.LONG, 'name=restart.mesh&max_iter=3000&mode=literal&finish=0&tol_move=0');
        await tab2.goto(URL + '/ui/jobs/' + j5);
        await tab2.waitForFunction(() => +document.getElementById('chart').dataset.points > 3, null, { timeout: 30000 });
        const before = await tab2.$eval('#chart', (c) => +c.dataset.points);
        const nerr = errors.length;
        writeFileSync(path.join(OUT, 'kill-now'), '');
        await until(() => existsSync(path.join(OUT, 'restarted')), 60000, 'the daemon to come back');
        const said = await tab2.waitForSelector('#job-follow[data-kind="restart"]:not([hidden])', { timeout: 60000 })
            .then(() => tab2.evaluate(() => [document.getElementById('job-follow').textContent, document.getElementById('job-follow').dataset.attempt]))
            .catch((e) => [e.message, '']);
        const job5 = (await api('/v1/jobs/' + j5)).body;
        check(/runs again from the start: attempt 2 \(attempt 1 stopped/.test(said[0]) && said[1] === '2' && job5.attempts === 2,
            'restart: the job page says "' + said[0].slice(0, 80) + '…" (the job\'s attempts: ' + job5.attempts + ')', said.join(' | '));
        // the chart starts over: the new run's records from 0
        const after = await tab2.waitForFunction(() => {
            const n = +document.getElementById('chart').dataset.points;
            return n > 0 && n;
        }, null, { timeout: 30000 }).then((x) => x.jsonValue()).catch(() => 0);
        const prog = (await api('/v1/jobs/' + j5 + '/progress?after=-1&attempt=2')).body;
        check(after > 0 && prog && prog.attempt === 2 && after <= prog.count + 1,
            'restart: the chart starts over with attempt 2 (' + before + ' records of attempt 1 dropped, ' + after + ' shown of ' + (prog && prog.count) + ')',
            after + ' ' + JSON.stringify(prog && { attempt: prog.attempt, count: prog.count }));
        // a page opened after the takeover says whose records it shows
        const tab4 = watch(await context.newPage(), 'late tab');
        await tab4.goto(URL + '/ui/jobs/' + j5);
        const late = await tab4.waitForSelector('#job-follow[data-kind="attempt"]:not([hidden])', { timeout: 20000 })
            .then(() => tab4.textContent('#job-follow')).catch((e) => e.message);
        check(/the chart shows attempt 2 \(attempt 1 stopped/.test(late), 'restart: a page opened afterwards says "' + late.slice(0, 70) + '…"', late);
        await tab4.close();
        await api('/v1/jobs/' + j5 + ':cancel', { method: 'POST' });
        await tab2.waitForFunction(() => document.getElementById('job-state').textContent === 'cancelled', null, { timeout: 30000 })
            .then(() => pass('restart: the job page still follows the job (cancelled on attempt 2)'))
            .catch((e) => fail('restart: cancel', e.message));
        // the daemon's death: the tabs' fetches to it failed meanwhile
        for (let i = errors.length - 1; i >= nerr; i--) if (/ERR_CONNECTION|ERR_INCOMPLETE_CHUNKED|Failed to fetch|network/i.test(errors[i])) errors.splice(i, 1);
        // the deletions: the tabs' next look at the job is a 404
        const real = errors.filter((e) => !/status of 404/.test(e));
        check(!real.length, 'no console errors (but the deleted jobs\' 404s and the refused connections while qdcd was down)', real.join(' | '));
    }
} catch (e) {
    fail('browser run (' + (env.UI_MODE || 'tabs') + ')', e.stack || e);
} finally {
    writeFileSync(path.join(OUT, 'figures-' + (env.UI_MODE || 'tabs') + '.json'), JSON.stringify(figures, null, 1));
    await browser.close();
}
process.exit(failed());
