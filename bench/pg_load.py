#!/usr/bin/env python3
"""pg_load.py - job load for bench/pg_bench.sh.

  pg_load.py throughput N MESH QUERY URL [URL...]
      Submits N jobs (MESH, a binary QMESH) round-robin to the nodes, all at
      once, and waits until every job is done. Prints JSON: jobs, succeeded,
      seconds (first submission to the last job's end), jobs_per_min.
  pg_load.py overhead N MESH QUERY URL_A URL_B
      2N jobs one after the other, alternating between the two nodes (so both
      see the same machine): submit, long-poll /progress until done, fetch
      the result. A job's overhead is that wall time less its run (started
      to finished, the optimizer's time, which varies with the load of the
      machine). Prints JSON per node: median end-to-end and overhead (ms).
"""
import http.client
import json
import sys
import time
import urllib.parse

QM = "application/vnd.qdc.mesh"


def req(url, method, path, body=None, headers=None, timeout=120):
    u = urllib.parse.urlsplit(url)
    c = http.client.HTTPConnection(u.hostname, u.port, timeout=timeout)
    c.request(method, path, body=body, headers=headers or {})
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, data


def submit(url, body, query):
    st, data = req(url, "POST", "/v1/jobs?" + query, body, {"Content-Type": QM})
    if st != 202:
        raise SystemExit("submission answered %d: %s" % (st, data[:200]))
    return json.loads(data)["id"]


def throughput(n, mesh, query, urls):
    body = open(mesh, "rb").read()
    t0 = time.time()
    ids = [(urls[i % len(urls)], submit(urls[i % len(urls)], body, query)) for i in range(n)]
    pending, ok, last = {jid: url for url, jid in ids}, 0, t0
    while pending:
        time.sleep(0.1)
        for jid, url in list(pending.items()):
            st, data = req(url, "GET", "/v1/jobs/" + jid)
            j = json.loads(data) if st == 200 else {}
            if j.get("done"):
                ok += j["state"] == "succeeded"
                last = max(last, j.get("finished", 0))
                del pending[jid]
        if time.time() - t0 > 1800:
            raise SystemExit("jobs still pending after 30 min")
    secs = last - t0
    print(json.dumps({"jobs": n, "succeeded": ok, "seconds": round(secs, 2),
                      "jobs_per_min": round(n / secs * 60, 1)}))


def one_job(url, body, query):
    t0 = time.monotonic()
    jid = submit(url, body, query)
    after = -1
    while True:
        st, data = req(url, "GET", "/v1/jobs/%s/progress?after=%d&wait=30" % (jid, after))
        p = json.loads(data)
        after = p["next_after"]
        if p["done"]:
            break
    st, data = req(url, "GET", "/v1/jobs/%s/result" % jid)
    if st != 200:
        raise SystemExit("result answered %d" % st)
    wall = (time.monotonic() - t0) * 1000
    j = json.loads(req(url, "GET", "/v1/jobs/" + jid)[1])
    return wall, wall - (j["finished"] - j["started"]) * 1000


def overhead(n, mesh, query, urls):
    body = open(mesh, "rb").read()
    res = {u: ([], []) for u in urls}
    for _ in range(n):
        for u in urls:
            w, o = one_job(u, body, query)
            res[u][0].append(w)
            res[u][1].append(o)
    med = lambda v: round(sorted(v)[len(v) // 2], 2)
    print(json.dumps([{"jobs": n, "median_ms": med(res[u][0]), "overhead_ms": med(res[u][1])}
                      for u in urls]))


if __name__ == "__main__":
    a = sys.argv[1:]
    if len(a) >= 5 and a[0] == "throughput":
        throughput(int(a[1]), a[2], a[3], a[4:])
    elif len(a) == 6 and a[0] == "overhead":
        overhead(int(a[1]), a[2], a[3], a[4:])
    else:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
