#!/usr/bin/env python3
"""xnode.py - cross-node reads of qdcd jobs (PostgreSQL store), for pg3.sh
and bench/pg_bench.sh.

  xnode.py wake URL_WORKER URL_OTHER ID
      Long-polls /progress of job ID on both nodes at once, record after
      record, until the job is done. A record that woke both parked polls
      gives one sample: how much later the other node's poll returned than
      the worker node's (which its own worker wakes when it publishes the
      record). Prints JSON: samples, median_ms, p90_ms, max_ms, records.
  xnode.py events URL ID
      Follows /events to its end; prints JSON: progress (events), seqs in
      order (true/false), end (the end event's state).
"""
import http.client
import json
import sys
import threading
import time
import urllib.parse


def get(url, path, timeout=60):
    u = urllib.parse.urlsplit(url)
    c = http.client.HTTPConnection(u.hostname, u.port, timeout=timeout)
    c.request("GET", path)
    r = c.getresponse()
    body = r.read()
    c.close()
    return r.status, body


def poll(url, jid, after, out, key):
    t0 = time.monotonic()
    st, body = get(url, "/v1/jobs/%s/progress?after=%d&wait=20" % (jid, after))
    out[key] = (t0, time.monotonic(), st, json.loads(body) if st == 200 else None)


def wake(worker, other, jid):
    after, samples, records = -1, [], 0
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        res = {}
        ts = [threading.Thread(target=poll, args=(u, jid, after, res, k))
              for k, u in (("w", worker), ("o", other))]
        for t in ts:
            t.start()
        for t in ts:
            t.join()
        (s0, e0, st0, b0), (s1, e1, st1, b1) = res["w"], res["o"]
        if st0 != 200 or st1 != 200:
            print(json.dumps({"error": "status %d/%d" % (st0, st1)}))
            return 1
        n0, n1 = b0["count"], b1["count"]
        # both parked (neither answered at once) and both got the same next record
        if n0 and n1 and e0 - max(s0, s1) > 0.01 and b0["records"][0] == b1["records"][0]:
            samples.append((e1 - e0) * 1000)
        if n0:
            after = b0["records"][-1]["seq"] if not n1 else min(
                b0["records"][-1]["seq"], b1["records"][-1]["seq"])
            records = max(records, after + 1)
        if b0["done"] and b1["done"] and not n0 and not n1:
            break
        if b0["done"] and b1["done"]:
            continue
    samples.sort()
    r = {"samples": len(samples), "records": records}
    if samples:
        r.update(median_ms=round(samples[len(samples) // 2], 2),
                 p90_ms=round(samples[int(len(samples) * 0.9)], 2),
                 max_ms=round(samples[-1], 2), min_ms=round(samples[0], 2))
    print(json.dumps(r))
    return 0


def events(url, jid):
    u = urllib.parse.urlsplit(url)
    c = http.client.HTTPConnection(u.hostname, u.port, timeout=120)
    c.request("GET", "/v1/jobs/%s/events" % jid)
    r = c.getresponse()
    seqs, end, ev, data = [], None, None, None
    for raw in r:
        line = raw.decode().rstrip("\n")
        if line.startswith("event: "):
            ev = line[7:]
        elif line.startswith("data: "):
            data = json.loads(line[6:])
        elif line == "" and ev:
            if ev == "progress":
                seqs.append(data["seq"])
            elif ev == "end":
                end = data.get("state")
                break
            ev = data = None
    c.close()
    print(json.dumps({"progress": len(seqs), "in_order": seqs == list(range(len(seqs))),
                      "end": end}))
    return 0


if __name__ == "__main__":
    a = sys.argv[1:]
    if a and a[0] == "wake" and len(a) == 4:
        sys.exit(wake(a[1], a[2], a[3]))
    if a and a[0] == "events" and len(a) == 3:
        sys.exit(events(a[1], a[2]))
    print(__doc__, file=sys.stderr)
    sys.exit(2)
