// tap.mjs - what the browser scripts (console.mjs, crossorigin.mjs, tabs.mjs)
// share: playwright-core from UI_MODULES (npm ci of tests/ui/package-lock.json)
// and "ok - ..." / "FAIL - ..." lines like the shell suites.
import { createRequire } from 'node:module';
import path from 'node:path';

export const { chromium } = createRequire(path.join(process.env.UI_MODULES, 'package.json'))('playwright-core');

let nfail = 0;
export const pass = (m) => console.log('ok - ' + m);
export const fail = (m, why) => { console.log('FAIL - ' + m + ': ' + String(why).replace(/\s+/g, ' ').slice(0, 400)); nfail++; };
export const check = (cond, m, why) => (cond ? pass(m) : fail(m, why));
// fn's first truthy value, tried every 50 ms; throws after ms
export async function until(fn, ms, what) {
    const t0 = Date.now();
    for (;;) {
        const v = await fn();
        if (v) return v;
        if (Date.now() - t0 > ms) throw new Error('timed out waiting for ' + what);
        await new Promise((r) => setTimeout(r, 50));
    }
}
// the exit status: 1 after a FAIL line
export const failed = () => (nfail ? 1 : 0);
