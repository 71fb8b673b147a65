#!/usr/bin/python3
"""load.py URL PID SECONDS MESH: mixed traffic against a running qdcd.

Clients at once: job submissions (small meshes), event streams opened and
closed at once or after a while, long-polls, uploads aborted half-way, refused
uploads (wrong type, too large) whose client hangs up without reading, and a
prober that GETs /livez every 100 ms and records its latency. Before the
traffic, the same prober alone for IDLE seconds (every 20 ms) gives the
baseline its latencies are judged against (the machine may be busy with other
work: both phases see it). At the end
(traffic stopped, jobs drained): every accepted job exists and succeeded,
none is left queued/running, and the daemon's fds, threads and RSS are back
near their baseline. Prints one JSON line."""
import json, os, random, socket, sys, threading, time, urllib.request

url, pid, seconds, mesh = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
host, port = url.split('//')[1].split(':')
port = int(port)
body = open(mesh, 'rb').read()
stop = threading.Event()
lock = threading.Lock()
accepted, errors, lat = [], [], []
counts = {'submits': 0, 'streams': 0, 'polls': 0, 'aborted': 0, 'refused': 0, '429': 0,
          'closed_early': 0}


def proc_stats():
    fds = len(os.listdir('/proc/%d/fd' % pid))
    st = open('/proc/%d/status' % pid).read().split('\n')
    val = {l.split(':')[0]: l.split(':')[1].strip() for l in st if ':' in l}
    return fds, int(val['Threads']), int(val['VmRSS'].split()[0])


def bump(k):
    with lock:
        counts[k] += 1


def http(method, path, data=None, ctype=None, timeout=30):
    req = urllib.request.Request(url + path, data=data, method=method)
    if ctype:
        req.add_header('Content-Type', ctype)
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()
    except (urllib.error.URLError, OSError) as e:
        # a connection over --max-connections is closed at once (a refused
        # upload's reply itself waits for its body: http.c, hold_reply)
        return 0, str(e).encode()


def raw(lines, payload=b'', read=False, hold=0.0):
    s = socket.create_connection((host, port), timeout=10)
    s.sendall(lines + payload)
    if hold:
        time.sleep(hold)
    if read:
        try:
            s.recv(4096)
        except OSError:
            pass
    s.close()


def submitter():
    while not stop.is_set():
        st, b = http('POST', '/v1/jobs?max_iter=3', body, 'model/x-medit')
        if st == 202:
            with lock:
                accepted.append(json.loads(b)['id'])
            bump('submits')
        elif st in (429, 0):
            bump('429' if st else 'closed_early')
            time.sleep(0.2)
        else:
            with lock:
                errors.append('submit %d %s' % (st, b[:200]))
        time.sleep(0.05)


def recent(rnd):
    """One of the last 5 accepted jobs, or None after a short wait."""
    with lock:
        ids = accepted[-5:]
    if not ids:
        time.sleep(0.1)
        return None
    return rnd.choice(ids)


def streamer():
    rnd = random.Random(1)
    while not stop.is_set():
        jid = recent(rnd)
        if not jid:
            continue
        req = b'GET /v1/jobs/%s/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n' % jid.encode()
        try:
            raw(req, hold=rnd.choice([0, 0, 0.3, 1.0]), read=rnd.random() < 0.5)
            bump('streams')
        except OSError as e:
            with lock:
                errors.append('stream %s' % e)


def poller():
    rnd = random.Random(2)
    while not stop.is_set():
        jid = recent(rnd)
        if not jid:
            continue
        st, _ = http('GET', '/v1/jobs/%s/progress?after=-1&wait=1' % jid)
        if st not in (200, 404, 0):
            with lock:
                errors.append('poll %d' % st)
        bump('polls')


def aborter():
    rnd = random.Random(3)
    while not stop.is_set():
        try:
            k = rnd.randrange(3)
            if k == 0:   # upload cut half-way
                raw(b'POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: model/x-medit\r\n'
                    b'Content-Length: %d\r\n\r\n' % len(body), body[:len(body) // 2], hold=0.1)
                bump('aborted')
            elif k == 1:  # refused type, client gone without reading
                raw(b'POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: image/png\r\n'
                    b'Content-Length: 100000\r\n\r\n', b'x' * 5000)
                bump('refused')
            else:         # refused size
                raw(b'POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: model/x-medit\r\n'
                    b'Content-Length: 100000000000000\r\n\r\n', b'x' * 5000)
                bump('refused')
        except OSError:
            pass
        time.sleep(0.02)


def prober(until=None, every=0.1, out=None):
    out = lat if out is None else out
    while not stop.is_set() and (until is None or time.monotonic() < until):
        t = time.monotonic()
        try:
            st, _ = http('GET', '/livez', timeout=5)
        except OSError:
            st = 0
        d = time.monotonic() - t
        with lock:
            out.append(d if st == 200 else 5.0)
        time.sleep(max(0.0, every - d))


def p99(a):
    a = sorted(a)
    return a[int(0.99 * (len(a) - 1))] if a else None


IDLE = 5.0
idle = []
prober(time.monotonic() + IDLE, 0.02, idle)
base = proc_stats()
threads = [threading.Thread(target=f) for f in
           (submitter, submitter, streamer, streamer, streamer, poller, poller, aborter, prober)]
for t in threads:
    t.start()
time.sleep(seconds)
stop.set()
for t in threads:
    t.join()
# drain: every accepted job ends. However slow the machine, jobs keep ending;
# a job is stuck only when none has ended for 120 s.
t0 = time.monotonic()
left = list(accepted)
states = {}
while left and time.monotonic() - t0 < 120:
    nxt = []
    for jid in left:
        st, b = http('GET', '/v1/jobs/' + jid)
        s = json.loads(b).get('state') if st == 200 else 'missing %d' % st
        if s in ('queued', 'running'):
            nxt.append(jid)
        else:
            states[jid] = s
    if len(nxt) < len(left):
        t0 = time.monotonic()
    left = nxt
    if left:
        time.sleep(1)
# connections close and threads end: wait (bounded) until back at the baseline
t0 = time.monotonic()
end = proc_stats()
while (end[0] > base[0] + 2 or end[1] > base[1]) and time.monotonic() - t0 < 30:
    time.sleep(0.1)
    end = proc_stats()
lat.sort()
bad = {s: 0 for s in set(states.values())}
for s in states.values():
    bad[s] += 1
print(json.dumps({
    'seconds': seconds, 'counts': counts, 'accepted': len(accepted), 'states': bad,
    'stuck': len(left), 'errors': errors[:5], 'n_errors': len(errors),
    'livez_n': len(lat), 'livez_p99_ms': lat and round(p99(lat) * 1000, 1),
    'idle_n': len(idle), 'idle_p99_ms': idle and round(p99(idle) * 1000, 1),
    'livez_max_ms': lat and round(lat[-1] * 1000, 1),
    'base': {'fds': base[0], 'threads': base[1], 'rss_kb': base[2]},
    'end': {'fds': end[0], 'threads': end[1], 'rss_kb': end[2]}}))
