#!/usr/bin/python3
"""pollers.py URL JOB N PID - N concurrent long-poll clients (one keep-alive
connection each) follow JOB from its current position until it is done, while
the daemon's thread count (/proc/PID/task) and parked-connection gauge
(/metrics) are sampled. Prints one JSON object:
  clients, complete (clients whose seqs were contiguous up to the job's last
  record), first/last seq seen, threads_before, threads_max, parked_max,
  requests (long-poll round trips), errors."""
import http.client
import json
import os
import sys
import threading
import time
from urllib.parse import urlparse

url, job, n, pid = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
u = urlparse(url)
lock = threading.Lock()
results = []
stats = {"requests": 0, "errors": 0}
done_evt = threading.Event()


def get(conn, path):
    conn.request("GET", path)
    r = conn.getresponse()
    return r.status, r.read()


def nthreads():
    return len(os.listdir("/proc/%s/task" % pid))


def client(start):
    conn = http.client.HTTPConnection(u.hostname, u.port, timeout=60)
    after, seqs, last, reqs = start, [], None, 0
    try:
        while True:
            st, body = get(conn, "/v1/jobs/%s/progress?after=%d&wait=30" % (job, after))
            reqs += 1
            if st != 200:
                raise RuntimeError("status %d" % st)
            d = json.loads(body)
            seqs += [r["seq"] for r in d["records"]]
            after = d["next_after"]
            if d["done"]:
                last = after
                break
    except Exception as e:  # noqa: BLE001 - counted, reported
        with lock:
            stats["errors"] += 1
            print("client error:", e, file=sys.stderr)
    with lock:
        stats["requests"] += reqs
        results.append((start, seqs, last))


def sampler(out):
    c = http.client.HTTPConnection(u.hostname, u.port, timeout=10)
    while not done_evt.is_set():
        out["threads_max"] = max(out["threads_max"], nthreads())
        try:
            st, body = get(c, "/metrics")
            for line in body.decode().splitlines():
                if line.startswith("qdcd_parked_connections "):
                    out["parked_max"] = max(out["parked_max"], int(float(line.split()[1])))
        except Exception:  # noqa: BLE001 - sampling only
            c = http.client.HTTPConnection(u.hostname, u.port, timeout=10)
        time.sleep(0.05)


c0 = http.client.HTTPConnection(u.hostname, u.port, timeout=60)
st, body = get(c0, "/v1/jobs/%s/progress?after=-1" % job)
start = json.loads(body)["next_after"]
samp = {"threads_before": nthreads(), "threads_max": 0, "parked_max": 0}
ts = [threading.Thread(target=client, args=(start,)) for _ in range(n)]
s = threading.Thread(target=sampler, args=(samp,))
s.start()
for t in ts:
    t.start()
for t in ts:
    t.join()
done_evt.set()
s.join()
final = max((r[2] for r in results if r[2] is not None), default=None)
complete = sum(1 for st0, seqs, last in results
               if last == final and seqs == list(range(st0 + 1, final + 1)))
print(json.dumps({"clients": n, "complete": complete, "start": start, "last": final,
                  "requests": stats["requests"], "errors": stats["errors"], **samp}))
