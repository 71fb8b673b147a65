// crossorigin.mjs - a web page on another origin cannot use a local qdcd:
// a tiny HTTP server on another loopback port serves a page whose script
// POSTs a mesh to qdcd the way a hostile page would (fetch, mode no-cors,
// Content-Type text/plain: a "simple" request, sent without a preflight).
// qdcd must answer 403 and create no job. Run by tests/server/ui.sh with
// UI_MODULES, QDC_URL, SAMPLE and CHROMIUM in the environment; prints
// "ok - ..." / "FAIL - ..." lines.
import { readFileSync } from 'node:fs';
import http from 'node:http';
import { chromium, pass, fail, failed } from './tap.mjs';

const env = process.env;
const URL = env.QDC_URL;

const page = `<!doctype html><meta charset="utf-8"><title>elsewhere</title>
<script>
window.attack = async (url, mesh) => {
  try {
    await fetch(url + '/v1/jobs', { method: 'POST', mode: 'no-cors',
      headers: { 'Content-Type': 'text/plain' }, body: mesh });
    return 'sent';
  } catch (e) { return 'error ' + e.message; }
};
</script>`;
const server = http.createServer((req, res) => {
    res.writeHead(200, { 'Content-Type': 'text/html' });
    res.end(page);
});
await new Promise((r) => server.listen(0, '127.0.0.1', r));
const other = 'http://127.0.0.1:' + server.address().port;

const count = async () => (await (await fetch(URL + '/v1/jobs')).json()).jobs.length;
const browser = await chromium.launch({
    executablePath: env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox'],
});
try {
    const before = await count();
    const pg = await browser.newPage();
    await pg.goto(other + '/', { waitUntil: 'load' });
    const mesh = readFileSync(env.SAMPLE, 'utf8');
    const seen = pg.waitForResponse((r) => r.url().startsWith(URL + '/v1/jobs'), { timeout: 30000 });
    const how = await pg.evaluate(([u, m]) => window.attack(u, m), [URL, mesh]);
    const res = await seen;
    const after = await count();
    if (res.status() === 403 && after === before)
        pass(`a page on ${other} POSTing a mesh to qdcd (fetch no-cors, text/plain): ${how}, 403, no job created (${after} jobs)`);
    else
        fail('cross-origin page', `status ${res.status()}, jobs ${before} -> ${after}, ${how}`);
} catch (e) {
    fail('cross-origin browser run', e.stack || e);
} finally {
    await browser.close();
    server.close();
}
process.exit(failed());
