#!/usr/bin/python3
"""parkmem.py URL RUNNING QUEUED PID N [KIND] - N parked long-polls on QUEUED
and what they cost the daemon (PID). KIND "next" (default): clients that poll
in a loop, as HTTP clients with keep-alive do: each asks RUNNING for its
records (answered at once), then long-polls QUEUED (parks) on the same
connection, or on a new one if the daemon answered with Connection: close.
KIND "first": each poll on a new connection. Then every client hangs up
while parked. Prints one JSON object:
  parked, reconnected (clients told to reconnect), answered (polls answered
  before RSS was sampled: the sample is then void), rss_kb_before,
  rss_kb_parked, kb_each (extra RSS per parked poll), threads_before,
  threads_parked, parked_after_hangup (gauge 5 s after the hang-ups, polled),
  hangup_s (seconds until it reached 0), hangups (qdcd_parked_hangups_total)."""
import json
import os
import select
import socket
import sys
import time
from urllib.parse import urlparse

url, running, queued, pid, n = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5])
kind = sys.argv[6] if len(sys.argv) > 6 else "next"
u = urlparse(url)


def rss_kb():
    for line in open("/proc/%s/status" % pid):
        if line.startswith("VmRSS"):
            return int(line.split()[1])
    return 0


def nthreads():
    return len(os.listdir("/proc/%s/task" % pid))


def reply(s):
    """Lower-cased header lines of one Content-Length framed reply on s."""
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = s.recv(65536)
        if not chunk:
            raise RuntimeError("connection closed before a reply")
        data += chunk
    head, body = data.split(b"\r\n\r\n", 1)
    lines = head.decode().lower().split("\r\n")
    cl = [int(x.split(":")[1]) for x in lines if x.startswith("content-length:")]
    while cl and len(body) < cl[0]:
        body += s.recv(65536)
    return lines


def metric(name):
    s = socket.create_connection((u.hostname, u.port))
    s.sendall(b"GET /metrics HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n")
    data = b""
    while True:
        chunk = s.recv(65536)
        if not chunk:
            break
        data += chunk
    s.close()
    for line in data.decode().splitlines():
        if line.startswith(name + " "):
            return float(line.split()[1])
    return -1.0


def sample(f, pick):
    vals = []
    for _ in range(5):
        time.sleep(0.1)
        vals.append(f())
    return pick(vals)


def get(path):
    return ("GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n" % path).encode()


out = {"rss_kb_before": sample(rss_kb, min), "threads_before": nthreads()}
first = get("/v1/jobs/%s/progress?after=-1" % running)
park = get("/v1/jobs/%s/progress?after=-1&wait=60" % queued)
socks, reconnected = [], 0
for _ in range(n):
    s = socket.create_connection((u.hostname, u.port))
    if kind == "next":
        s.sendall(first)
        if "connection: close" in reply(s):
            s.close()
            s = socket.create_connection((u.hostname, u.port))
            reconnected += 1
    s.sendall(park)
    socks.append(s)
t = time.time()
while metric("qdcd_parked_connections") < n and time.time() - t < 30:
    time.sleep(0.2)
out["parked"] = int(metric("qdcd_parked_connections"))
time.sleep(0.5)
out["rss_kb_parked"] = sample(rss_kb, max)
out["threads_parked"] = nthreads()
out["answered"] = sum(1 for s in socks if select.select([s], [], [], 0)[0])
out["reconnected"] = reconnected
out["kb_each"] = round((out["rss_kb_parked"] - out["rss_kb_before"]) / max(out["parked"], 1), 1)

for s in socks:
    s.close()
t = time.time()
while metric("qdcd_parked_connections") > 0 and time.time() - t < 5:
    time.sleep(0.1)
out["hangup_s"] = round(time.time() - t, 1)
out["parked_after_hangup"] = int(metric("qdcd_parked_connections"))
out["hangups"] = int(metric("qdcd_parked_hangups_total"))
print(json.dumps(out))
