// views.mjs - checks of the console's charts, 3D view, phone layout and
// accessibility, used by console.mjs (each takes the page and the helpers
// {pass, fail, check, apiJSON, figures}). Expected values come from the API
// (records, report, the result mesh), never from the page's own arithmetic.
import { readFileSync } from 'node:fs';
import path from 'node:path';

// What the 3D canvas shows, after the next frames: the box of what is drawn
// (not the background) as fractions of the canvas, and pixels by colour:
// orange (the input's worst tets), red (the result's), green (good tets of
// the clip plane's cut).
export function view3dPixels(page) {
    return page.evaluate(() => new Promise((res) => requestAnimationFrame(() => requestAnimationFrame(() => {
        const c = document.getElementById('view3d');
        const t = document.createElement('canvas');
        t.width = c.width;
        t.height = c.height;
        const g = t.getContext('2d');
        g.drawImage(c, 0, 0);
        const d = g.getImageData(0, 0, t.width, t.height).data;
        let x0 = Infinity, x1 = -1, y0 = Infinity, y1 = -1, orange = 0, red = 0, green = 0;
        for (let i = 0, p = 0; i < d.length; i += 4, p++) {
            const [R, G, B] = [d[i], d[i + 1], d[i + 2]];
            if (Math.abs(R - 16) + Math.abs(G - 22) + Math.abs(B - 31) > 30) {
                const x = p % t.width, y = Math.floor(p / t.width);
                if (x < x0) x0 = x;
                if (x > x1) x1 = x;
                if (y < y0) y0 = y;
                if (y > y1) y1 = y;
            }
            if (G > R + 30 && G > B + 30) green++;
            else if (G - B > 40 && R > G) orange++;
            else if (R - G > 60 && Math.abs(G - B) < 25) red++;
        }
        res({ fx: x1 < 0 ? 0 : (x1 - x0 + 1) / t.width, fy: y1 < 0 ? 0 : (y1 - y0 + 1) / t.height, orange, red, green, layers: c.dataset.layers });
    }))));
}

// The mean ratio of tet t of a QMESH file (little-endian: magic, nv, nt at
// 16 and 24, then xyz doubles and int32 tets), computed here from the
// definition 12 (3V)^(2/3) / sum of squared edge lengths.
function meanRatioOf(buf, t) {
    const dv = new DataView(buf.buffer, buf.byteOffset, buf.byteLength);
    const nv = Number(dv.getBigUint64(16, true));
    const at = (v, k) => dv.getFloat64(32 + 24 * v + 8 * k, true);
    const vs = [0, 1, 2, 3].map((k) => dv.getInt32(32 + 24 * nv + 16 * t + 4 * k, true));
    const P = vs.map((v) => [at(v, 0), at(v, 1), at(v, 2)]);
    const s = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    const [u, v, w] = [s(P[1], P[0]), s(P[2], P[0]), s(P[3], P[0])];
    const det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
    let l2 = 0;
    for (let i = 0; i < 4; i++) for (let j = i + 1; j < 4; j++) { const e = s(P[j], P[i]); l2 += e[0] * e[0] + e[1] * e[1] + e[2] * e[2]; }
    return (12 * Math.pow(Math.abs(det) / 2, 2 / 3)) / l2;
}

// Chart: axis titles, a tooltip with the record's values, the log toggle;
// histogram: both sets visible, its tooltip, its log toggle; text
// alternatives.
export async function chartChecks(page, id, h) {
    const recs = (await h.apiJSON('/v1/jobs/' + id + '/progress?after=-1')).body.records;
    const report = (await h.apiJSON('/v1/jobs/' + id + '/report')).body;
    const ds = await page.$eval('#chart', (c) => ({ x: c.dataset.xlabel, y: c.dataset.ylabels }));
    h.check(/progress record/.test(ds.x) && /mean ratio \(1 = regular tet\)/.test(ds.y) && /dihedral angle \(degrees\)/.test(ds.y) &&
        /inverted tets \(count\)/.test(ds.y), 'chart: axes titled with units (x: ' + ds.x + '; y: ' + ds.y + ')', JSON.stringify(ds));
    await page.$eval('#chart', (c) => c.scrollIntoView());
    const k = Math.min(recs.length - 1, Math.max(1, Math.round(recs.length * 0.6)));
    const box = await page.$eval('#chart', (c) => { const r = c.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; });
    const L = 58, R = 12;
    await page.mouse.move(box[0] + L + ((box[2] - L - R) * k) / Math.max(1, recs.length - 1), box[1] + 60);
    const tip = await page.waitForFunction(() => !document.getElementById('chart-tip').hidden && document.getElementById('chart-tip').textContent, null, { timeout: 3000 })
        .then((x) => x.jsonValue()).catch(() => '');
    const r = recs[k];
    h.check(tip.includes('record ' + k) && tip.includes(r.mean_ratio_mean.toFixed(4)) && tip.includes(r.dihedral_min.toFixed(2)) && tip.includes('inverted ' + r.n_inverted.toLocaleString('en-US')),
        'chart: pointing at record ' + k + ' shows its values: "' + tip.replace(/\s+/g, ' ') + '"', tip + ' vs ' + JSON.stringify(r));
    await page.mouse.move(0, 0);
    await page.click('#chart-log');
    const logY = await page.waitForFunction(() => /log scale/.test(document.getElementById('chart').dataset.ylabels) && document.getElementById('chart').dataset.ylabels, null, { timeout: 3000 })
        .then((x) => x.jsonValue()).catch(() => '');
    await page.click('#chart-log');
    h.check(/inverted tets \(count, log scale\)/.test(logY), 'chart: the log-scale toggle puts the inverted count on a log axis', logY);
    const alt = await page.getAttribute('#chart', 'aria-label');
    h.check(alt && alt.startsWith('Convergence chart of ' + recs.length + ' progress records') && alt.includes(recs[0].mean_ratio_mean.toFixed(4)) &&
        (await page.getAttribute('#chart', 'role')) === 'img', 'chart: role img with a text alternative in numbers ("' + alt.slice(0, 90) + '…")', alt);

    // histogram: "before" (grey fill) and "after" (blue line) both drawn
    await page.$eval('#hist', (c) => c.scrollIntoView());
    const px = await page.evaluate(() => {
        const c = document.getElementById('hist');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let grey = 0, blue = 0;
        for (let i = 0; i < d.length; i += 4) {
            const [R, G, B] = [d[i], d[i + 1], d[i + 2]];
            if (B > 200 && R < 90 && G > 80 && G < 150) blue++;
            // the fill, rgba(154, 164, 178, .45) on the transparent canvas (the
            // grid lines are opaque)
            else if (d[i + 3] > 90 && d[i + 3] < 140 && Math.abs(R - 154) < 12 && Math.abs(G - 164) < 12 && Math.abs(B - 178) < 12) grey++;
        }
        return { grey, blue };
    });
    const hb = report.before.dihedral_histogram, ha = report.after.dihedral_histogram;
    const over = hb.filter((v, i) => v > (ha[i] || 0)).length, under = ha.filter((v, i) => v > (hb[i] || 0)).length;
    h.check(px.grey > 500 && px.blue > 300, 'histogram: "before" filled (' + px.grey + ' grey px) and "after" as a line (' + px.blue +
        ' blue px), both visible: before is higher in ' + over + ' bins, after in ' + under, JSON.stringify(px));
    const hbox = await page.$eval('#hist', (c) => { const r = c.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; });
    const bin = hb.reduce((best, v, i) => (v + (ha[i] || 0) > hb[best] + (ha[best] || 0) ? i : best), 0);
    await page.mouse.move(hbox[0] + 58 + ((hbox[2] - 58 - 10) * (bin + 0.5)) / 180, hbox[1] + 40);
    const htip = await page.waitForFunction(() => !document.getElementById('hist-tip').hidden && document.getElementById('hist-tip').textContent, null, { timeout: 3000 })
        .then((x) => x.jsonValue()).catch(() => '');
    const fmt = (n) => n.toLocaleString('en-US');
    h.check(htip.startsWith(bin + '°–' + (bin + 1) + '°') && htip.includes(fmt(hb[bin]) + ' angles before') && htip.includes(fmt(ha[bin] || 0) + ' after'),
        'histogram: pointing at a bin shows both counts of the report ("' + htip + '")', htip + ' vs ' + hb[bin] + '/' + ha[bin]);
    await page.mouse.move(0, 0);
    const halt = await page.getAttribute('#hist', 'aria-label');
    h.check(/^Histogram of all dihedral angles/.test(halt) && halt.includes(report.after.dihedral_min.toFixed(2)), 'histogram: a text alternative in numbers', halt);
}

// 3D view: fills the canvas, Fit and Reset, a clip plane with the cut tets,
// a click that tells a tet's quality (checked against the result mesh), a
// lighter level of detail while turning.
export async function view3dChecks(page, id, h, URL, authH) {
    const ready = await page.waitForFunction(() => +document.getElementById('view3d').dataset.frames > 0 ||
        /not available/.test(document.getElementById('view3d-status').textContent), null, { timeout: 30000 }).then(() => true).catch(() => false);
    if (!ready || (await page.textContent('#view3d-status')).includes('not available')) {
        console.log('ok - 3D view tools # SKIP no WebGL in this chromium');
        return;
    }
    await page.$eval('#view3d', (c) => c.scrollIntoView({ block: 'center' }));
    const fit0 = await view3dPixels(page);
    h.check(Math.max(fit0.fx, fit0.fy) >= 0.8, '3D view: the mesh fills the canvas (' + (100 * fit0.fx).toFixed(0) + '% of its width, ' +
        (100 * fit0.fy).toFixed(0) + '% of its height)', JSON.stringify(fit0));
    const box = await page.$eval('#view3d', (c) => { const r = c.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; });
    const cx = box[0] + box[2] / 2, cy = box[1] + box[3] / 2;
    await page.mouse.move(cx, cy);
    for (let i = 0; i < 5; i++) await page.mouse.wheel(0, 400);
    await page.waitForTimeout(100);
    const far = await view3dPixels(page);
    await page.click('#view3d-fit');
    const fitted = await view3dPixels(page);
    // turn, then reset: the first view again
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    await page.mouse.move(cx + 120, cy + 40, { steps: 6 });
    const lodDrag = await page.waitForFunction(() => /^drag:/.test(document.getElementById('view3d').dataset.lod) && document.getElementById('view3d').dataset.lod,
        null, { timeout: 3000 }).then((x) => x.jsonValue()).catch(() => page.getAttribute('#view3d', 'data-lod'));
    await page.mouse.up();
    const lodUp = await page.waitForFunction(() => /^full:/.test(document.getElementById('view3d').dataset.lod) && document.getElementById('view3d').dataset.lod,
        null, { timeout: 5000 }).then((x) => x.jsonValue()).catch(() => page.getAttribute('#view3d', 'data-lod'));
    const camTurned = await page.getAttribute('#view3d', 'data-camera');
    const f0 = +(await page.getAttribute('#view3d', 'data-frames'));
    await page.click('#view3d-reset');
    await page.waitForFunction((n) => +document.getElementById('view3d').dataset.frames > n, f0, { timeout: 5000 }).catch(() => {});
    const reset = await view3dPixels(page);
    const near = (a, b) => Math.abs(a.fx - b.fx) < 0.02 && Math.abs(a.fy - b.fy) < 0.02;
    h.check(Math.max(far.fx, far.fy) < 0.6 * Math.max(fit0.fx, fit0.fy) && near(fitted, fit0) && near(reset, fit0),
        '3D view: zoomed out to ' + (100 * Math.max(far.fx, far.fy)).toFixed(0) + '%, Fit frames it again (' + (100 * Math.max(fitted.fx, fitted.fy)).toFixed(0) +
        '%), Reset after turning (' + camTurned + ') gives the first view', JSON.stringify({ fit0, far, fitted, reset }));
    const px = (s) => { const m = /(\d+)x(\d+) px/.exec(s || ''); return m ? +m[1] * +m[2] : 0; };
    h.check(/^drag:/.test(lodDrag) && /^full:/.test(lodUp) && px(lodDrag) * 3 < px(lodUp),
        '3D view: lighter while turning (' + lodDrag + ') than at rest (' + lodUp + ')', lodDrag + ' / ' + lodUp);

    // click the mesh (the middle, or around it: a torus has a hole there):
    // the tet under the pointer, its mean ratio as the result mesh has it
    let picked = null;
    for (const [dx, dy] of [[0, 0], [0.2, 0], [-0.2, 0], [0, 0.25], [0, -0.25], [0.1, 0.1]]) {
        await page.mouse.click(cx + dx * box[2], cy + dy * box[3]);
        picked = await page.waitForFunction(() => document.getElementById('view3d').dataset.picked, null, { timeout: 1500 })
            .then((x) => x.jsonValue()).catch(() => null);
        if (picked !== null) break;
    }
    const text = await page.textContent('#view3d-pick');
    if (picked === null) {
        h.fail('3D view: click a tet', 'nothing picked: ' + text);
    } else {
        const buf = Buffer.from(await (await fetch(URL + '/v1/jobs/' + id + '/result?format=qmesh', { headers: authH })).arrayBuffer());
        const q = meanRatioOf(buf, +picked);
        const m = /mean ratio ([+-][0-9.]+)/.exec(text);
        h.check(m && Math.abs(+m[1] - q) < 6e-5 && /dihedral angles( [0-9.]+°,?){6}/.test(text) && (await page.getAttribute('#view3d-pick', 'aria-live')) === 'polite',
            '3D view: a click tells the tet under the pointer, as the result mesh has it (tet ' + picked + ', mean ratio ' + q.toFixed(4) + '): "' + text.slice(0, 120) + '…"',
            text + ' vs ' + q);
    }
    // the clip plane: y at the middle, the tets it cuts drawn coloured by quality
    await page.selectOption('#view3d-clip', 'y');
    const cut = await page.waitForFunction(() => +document.getElementById('view3d').dataset.cut > 0 && document.getElementById('view3d-cut-info').textContent, null, { timeout: 10000 })
        .then((x) => x.jsonValue()).catch(() => '');
    const colours = await view3dPixels(page);
    h.check(/^\d[\d,]* tets cut by the plane y = /.test(cut) && colours.green > 200, '3D view: clip plane y: "' + cut.slice(0, 70) + '…", drawn by quality (' +
        colours.green + ' green px: tets of mean ratio about 0.8 and up)', cut + ' ' + JSON.stringify(colours));
    await page.fill('#view3d-clip-pos', '20');
    await page.dispatchEvent('#view3d-clip-pos', 'input');
    const cut2 = await page.textContent('#view3d-cut-info');
    h.check(cut2 !== cut && /tets cut by the plane y = /.test(cut2), '3D view: moving the plane cuts other tets ("' + cut2.slice(0, 50) + '…")', cut2);
    await page.selectOption('#view3d-clip', '');
    // the boundary coloured by how far it moved: the largest move shown is at
    // most the largest of any vertex between the input and the result meshes
    const qm = async (what) => Buffer.from(await (await fetch(URL + '/v1/jobs/' + id + '/' + what + '?format=qmesh', { headers: authH })).arrayBuffer());
    const [bi, bo] = [await qm('input'), await qm('result')];
    let maxAll = 0;
    for (let off = 32; off < 32 + 24 * Number(bo.readBigUInt64LE(16)); off += 24)
        maxAll = Math.max(maxAll, Math.hypot(bo.readDoubleLE(off) - bi.readDoubleLE(off), bo.readDoubleLE(off + 8) - bi.readDoubleLE(off + 8),
            bo.readDoubleLE(off + 16) - bi.readDoubleLE(off + 16)));
    // (the worst tets hidden: they are orange and red too)
    await page.click('#view3d-before');
    await page.click('#view3d-after');
    const plainPx = await view3dPixels(page);
    await page.click('#view3d-moved');
    await page.waitForFunction(() => document.getElementById('view3d').dataset.moved === '1', null, { timeout: 5000 }).catch(() => {});
    const movedPx = await view3dPixels(page);
    const info = await page.textContent('#view3d-moved-info');
    const shown = +(/moved up to ([0-9.e+-]+)/.exec(info) || [0, NaN])[1];
    await page.click('#view3d-moved');
    await page.click('#view3d-before');
    await page.click('#view3d-after');
    h.check(shown > 0 && shown <= maxAll * 1.001 && movedPx.orange > plainPx.orange + 200,
        '3D view: the boundary coloured by how far it moved ("' + info + '"; any vertex moved at most ' + maxAll.toPrecision(3) + '), ' +
        movedPx.orange + ' orange px against ' + plainPx.orange, info + ' ' + JSON.stringify({ plainPx, movedPx, maxAll }));
    const alt = await page.getAttribute('#view3d', 'aria-label');
    h.check((await page.getAttribute('#view3d', 'role')) === 'img' && /^3D view of the result: [\d,]+ boundary triangles/.test(alt),
        '3D view: role img with a text alternative ("' + alt.slice(0, 70) + '…")', alt);
}

// First frame and frame rates of the 3D view (software rendering here):
// turning (the lighter level of detail) and at rest, in frames drawn per
// second of pointer moves.
export async function view3dSpeed(page, h) {
    const ok = await page.waitForFunction(() => +document.getElementById('view3d').dataset.frames > 0, null, { timeout: 60000 }).then(() => true).catch(() => false);
    if (!ok) return null;
    await page.$eval('#view3d', (c) => c.scrollIntoView({ block: 'center' }));
    const box = await page.$eval('#view3d', (c) => { const r = c.getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]; });
    const frames = () => page.$eval('#view3d', (c) => +c.dataset.frames);
    const rate = async (drag) => {
        await page.mouse.move(box[0], box[1]);
        if (drag) await page.mouse.down();
        const f0 = await frames();
        const t0 = Date.now();
        for (let i = 0; Date.now() - t0 < 2000; i++) {
            if (drag) await page.mouse.move(box[0] + 40 * Math.sin(i / 5), box[1] + 10 * Math.cos(i / 7));
            else await page.keyboard.press(i % 2 ? 'ArrowLeft' : 'ArrowRight');
        }
        const n = (await frames()) - f0, s = (Date.now() - t0) / 1000;
        if (drag) await page.mouse.up();
        return n / s;
    };
    await page.focus('#view3d');
    const still = await rate(false);
    const turning = await rate(true);
    const ds = await page.$eval('#view3d', (c) => ({ first: +c.dataset.firstFrameMs, lod: c.dataset.lod, tris: +c.dataset.triangles }));
    return { first_frame_ms: ds.first, fps_full_detail: +still.toFixed(1), fps_turning: +turning.toFixed(1), boundary_triangles: ds.tris };
}

// A job with reruns (a tangled mesh, the finishing pass off): the chart says
// where each starts and why, and which record is the result.
export async function rerunChecks(page, id, h) {
    const recs = (await h.apiJSON('/v1/jobs/' + id + '/progress?after=-1')).body.records;
    const report = (await h.apiJSON('/v1/jobs/' + id + '/report')).body;
    const starts = recs.map((r, i) => (r.phase === 'rerun' ? i : -1)).filter((i) => i >= 0);
    // the rerun notes come with the progress records, the kept one only once
    // the report is in: wait for that one
    await page.waitForFunction(() => !document.getElementById('chart-notes').hidden && document.querySelector('#chart-notes li.kept'),
        null, { timeout: 30000 }).catch(() => {});
    const notes = await page.$$eval('#chart-notes li', (ls) => ls.map((l) => [l.className, l.textContent]));
    const reruns = notes.filter(([c]) => c === 'rerun');
    const kept = notes.find(([c]) => c === 'kept');
    const k = kept ? +/record (\d+)/.exec(kept[1])[1] : -1;
    h.check(starts.length > 0 && reruns.length === starts.length && reruns.every(([, t], i) => t.startsWith('Record ' + starts[i] + ': restarted from the input') &&
        t.includes(recs[starts[i] - 1].n_inverted.toLocaleString('en-US') + ' tets inverted')),
    'reruns explained in place: ' + starts.length + ' notes at records ' + starts.join(', ') + ' ("' + (reruns[0] ? reruns[0][1].slice(0, 100) : '') + '…")',
    JSON.stringify({ starts, notes }));
    h.check(k >= 0 && recs[k].iteration === report.run.best_iteration && recs[k].n_inverted === report.after.n_inverted &&
        Math.abs(recs[k].mean_ratio_mean - report.after.mean_ratio_mean) < 1e-4,
        'the record that is the result is named (' + (kept ? kept[1] : 'none') + '): the report\'s run.best_iteration (' + report.run.best_iteration +
        '), with its after\'s figures (' + report.after.n_inverted + ' inverted)', JSON.stringify({ kept, best_iteration: report.run.best_iteration }));
    const stats = await page.textContent('#job-stats');
    h.check(stats.includes(report.after.mean_ratio_mean.toFixed(4)) && stats.includes('→ ' + report.after.n_inverted.toLocaleString('en-US')),
        'job header shows the result\'s figures (mean ratio ' + report.after.mean_ratio_mean.toFixed(4) + ', ' + report.after.n_inverted + ' inverted), not the last record\'s',
        stats);
}

// No table column cut at the viewport's width: each table fits its box, and
// no cell reaches past its card.
export async function noColumnCut(page, what, h) {
    const bad = await page.evaluate(() => {
        const out = [];
        for (const t of document.querySelectorAll('table')) {
            if (!t.offsetParent) continue;
            const wrap = t.closest('.tablewrap') || t.parentElement;
            if (t.scrollWidth > t.clientWidth + 1 || wrap.scrollWidth > wrap.clientWidth + 1)
                out.push((t.id || t.className) + ': ' + t.scrollWidth + '/' + wrap.clientWidth + ' px');
            const card = t.closest('.card').getBoundingClientRect();
            for (const c of t.querySelectorAll('th, td')) {
                const r = c.getBoundingClientRect();
                if (r.width && r.height && (r.right > card.right + 0.5 || r.left < card.left - 0.5)) {
                    out.push((t.id || t.className) + ' cell "' + c.textContent.slice(0, 20) + '" at ' + r.left.toFixed(0) + '..' + r.right.toFixed(0) + ' outside ' + card.right.toFixed(0));
                    break;
                }
            }
        }
        return out;
    });
    const n = await page.$$eval('table', (ts) => ts.filter((t) => t.offsetParent).length);
    h.check(!bad.length && n > 0, what + ': no table column cut (' + n + ' tables fit their cards)', bad.join('; '));
}

// The live regions and roles the page relies on.
export async function ariaChecks(page, h) {
    const want = { 'submit-error': ['role', 'alert'], 'job-error': ['role', 'alert'], 'job-state': ['role', 'status'], 'upload-status': ['role', 'status'],
        'conn': ['role', 'status'], 'jobs-empty': ['role', 'status'], 'view3d-status': ['aria-live', 'polite'], 'view3d-pick': ['aria-live', 'polite'],
        'chart': ['role', 'img'], 'hist': ['role', 'img'], 'view3d': ['role', 'img'] };
    const got = await page.evaluate((w) => Object.keys(w).map((id) => [id, document.getElementById(id) && document.getElementById(id).getAttribute(w[id][0])]), want);
    const bad = got.filter(([id, v]) => v !== want[id][1]);
    h.check(!bad.length, 'ARIA: errors are alerts, status and state live regions, charts and the 3D view images with text (' + got.length + ' elements)', JSON.stringify(bad));
}

// axe-core in the page (a context that bypasses the page's CSP for its
// script): no serious or critical violation.
export async function axeChecks(browser, URL, pages, modules, h) {
    const src = path.join(modules, 'node_modules', 'axe-core', 'axe.min.js');
    let code;
    try {
        code = readFileSync(src, 'utf8');
    } catch (e) {
        console.log('ok - axe-core # SKIP not installed (' + e.message + ')');
        return;
    }
    const version = JSON.parse(readFileSync(path.join(modules, 'node_modules', 'axe-core', 'package.json'), 'utf8')).version;
    for (const [what, url, width, ready] of pages) {
        const ctx = await browser.newContext({ viewport: { width, height: 900 }, bypassCSP: true });
        const p = await ctx.newPage();
        await p.goto(URL + url);
        await p.waitForFunction(ready, null, { timeout: 20000 }).catch(() => {});
        await p.addScriptTag({ content: code });
        const res = await p.evaluate(() => window.axe.run(document, { resultTypes: ['violations'] }));
        const bad = res.violations.filter((v) => v.impact === 'serious' || v.impact === 'critical');
        const minor = res.violations.filter((v) => !bad.includes(v));
        h.check(!bad.length, 'axe-core ' + version + ', ' + what + ' (' + width + ' px): 0 serious or critical violations' +
            (minor.length ? ' (' + minor.map((v) => v.impact + ' ' + v.id).join(', ') + ')' : ''),
        bad.map((v) => v.impact + ' ' + v.id + ': ' + v.nodes.slice(0, 2).map((n) => n.target.join(' ')).join(', ')).join('; '));
        await ctx.close();
    }
}
