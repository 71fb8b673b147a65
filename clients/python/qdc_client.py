#!/usr/bin/python3
"""qdc_client - a Python client for qdcd, the qdc mesh optimization daemon.

Standard library only (urllib, struct, array); numpy is used when it is
installed and you ask for it. The HTTP API is described in proto/openapi.yaml,
the binary mesh format in proto/mesh-binary.md.

    from qdc_client import Client
    c = Client("http://127.0.0.1:8080")           # or $QDC_SERVER, token $QDC_TOKEN
    job = c.submit("in.msh", {"max_iter": 20})   # a path (.mesh .msh .vtk .vtu .json .qmesh
                                                  # .meshb .xml .inp .vol) ...
    job = c.submit((xyz, tets))                   # ... or arrays (lists or numpy)
    c.wait(job, on_progress=lambda r: print(r["iteration"], r["mean_ratio_min"]))
    mesh = c.result(job)                          # Mesh: .xyz, .tets, .regions, .fixed
    c.result(job, "out.mesh")                     # or a file, format by extension
    job = c.submit("m.xdmf")                      # XDMF naming an .h5 file: both sent
    c.result(job, "out.xdmf")                     # out.xdmf + out.h5 beside it
    rep = c.report(job)                           # quality before/after, boundary error
    print("\n".join(outcome_lines(rep)))          # the outcome in words, as qdc prints it

Every request is retried on 429, 5xx and connection failures, waiting what
the server's Retry-After says (else an exponential backoff); submit() sends an
Idempotency-Key so a retried upload never makes two jobs.

Command line:
    python3 qdc_client.py submit IN [-o OUT] [--report R.json] [--label TEXT] [--name NAME]
                                    [--opt max_iter=20 ...]
    python3 qdc_client.py status JOB | cancel JOB | jobs
    python3 qdc_client.py fetch JOB -o OUT [--report R.json]
"""

import array
import json
import os
import random
import re
import stat
import struct
import sys
import time
import urllib.error
import urllib.parse
import urllib.request
import uuid
import xml.etree.ElementTree as _ET

try:
    import numpy as _np
except ImportError:  # numpy is optional
    _np = None

MEDIA_QMESH = "application/vnd.qdc.mesh"
MAGIC = b"QDCMESH\0"
FLAG_REGION = 1
FLAG_FIXED = 2
_HEADER = struct.Struct("<8sIIQQ")


__all__ = ["Client", "Mesh", "QdcError", "JobFailed", "MEDIA_QMESH", "outcome_lines"]


class QdcError(Exception):
    """The server refused a request (status, problem+json body as a dict) or
    could not be reached (status 0)."""

    def __init__(self, status, problem=None, message=None):
        self.status = status
        self.problem = problem or {}
        text = message or "%s: %s" % (
            self.problem.get("title", "HTTP %d" % status),
            self.problem.get("detail", ""),
        )
        super().__init__("HTTP %d %s" % (status, text) if status else text)


class JobFailed(Exception):
    """The job ended failed or cancelled; .job is its last JSON."""

    def __init__(self, job):
        self.job = job
        err = job.get("error") or {}
        why = err.get("detail") or err.get("title") or job.get("stop_reason") or ""
        why = "" if why == job.get("state") else why
        super().__init__("job %s %s%s" % (job.get("id"), job.get("state"), ": " + why if why else ""))


def _le(arr):
    """array in little-endian byte order (the wire order)."""
    if sys.byteorder != "little":
        arr = array.array(arr.typecode, arr)
        arr.byteswap()
    return arr


class Mesh:
    """A tet mesh: xyz (nv*3 doubles), tets (nt*4 0-based ints), optional
    regions (nt ints) and fixed (nv flags, non-zero = must not move).

    Stored as flat array.array objects; numpy arrays or nested lists are
    accepted on input, and as_numpy() returns (nv,3) / (nt,4) ndarrays."""

    def __init__(self, xyz, tets, regions=None, fixed=None):
        self.xyz = self._flat("d", xyz, 3)
        self.tets = self._flat("i", tets, 4)
        self.regions = None if regions is None else self._flat("i", regions, 1)
        if fixed is None:
            self.fixed = None
        elif _is_np(fixed):
            self.fixed = self._flat("B", (fixed != 0).astype("u1"), 1)
        elif isinstance(fixed, array.array) and fixed.typecode == "B":
            self.fixed = fixed
        else:
            self.fixed = array.array("B", [1 if f else 0 for f in fixed])
        if len(self.xyz) % 3 or len(self.tets) % 4:
            raise ValueError("xyz needs 3 numbers a vertex and tets 4 indices a tet")
        if self.regions is not None and len(self.regions) != self.nt:
            raise ValueError("regions needs one tag a tet")
        if self.fixed is not None and len(self.fixed) != self.nv:
            raise ValueError("fixed needs one flag a vertex")

    @staticmethod
    def _flat(code, data, width):
        if isinstance(data, array.array) and data.typecode == code:
            return data
        if _is_np(data):
            dt = {"d": "<f8", "i": "<i4", "B": "u1"}[code]
            out = array.array(code)
            out.frombytes(_np.ascontiguousarray(data, dtype=dt).tobytes())
            return _le(out)  # the bytes were little-endian
        out = array.array(code)
        for item in data:
            if isinstance(item, (list, tuple)):
                if len(item) != width:
                    raise ValueError("rows of %d expected, got %d" % (width, len(item)))
                out.extend(item)
            else:
                out.append(item)
        return out

    @property
    def nv(self):
        return len(self.xyz) // 3

    @property
    def nt(self):
        return len(self.tets) // 4

    def to_bytes(self):
        """The binary format of proto/mesh-binary.md."""
        flags = (FLAG_REGION if self.regions is not None else 0) | (
            FLAG_FIXED if self.fixed is not None else 0)
        parts = [_HEADER.pack(MAGIC, 1, flags, self.nv, self.nt),
                 _le(self.xyz).tobytes(), _le(self.tets).tobytes()]
        if self.regions is not None:
            parts.append(_le(self.regions).tobytes())
        if self.fixed is not None:
            parts.append(self.fixed.tobytes())
        return b"".join(parts)

    @classmethod
    def from_bytes(cls, buf):
        """Parse the binary format; ValueError if it is not exactly one mesh."""
        if len(buf) < _HEADER.size:
            raise ValueError("binary mesh: truncated header")
        magic, version, flags, nv, nt = _HEADER.unpack_from(buf, 0)
        if magic != MAGIC or version != 1 or flags & ~(FLAG_REGION | FLAG_FIXED):
            raise ValueError("binary mesh: bad magic, version or flags")
        size = _HEADER.size + 24 * nv + 16 * nt
        size += 4 * nt if flags & FLAG_REGION else 0
        size += nv if flags & FLAG_FIXED else 0
        if size != len(buf):
            raise ValueError("binary mesh: %d bytes, header says %d" % (len(buf), size))
        off = _HEADER.size

        def take(code, n, width):
            nonlocal off
            a = array.array(code)
            a.frombytes(buf[off:off + n * width])
            off += n * width
            return _le(a)

        xyz = take("d", 3 * nv, 8)
        tets = take("i", 4 * nt, 4)
        regions = take("i", nt, 4) if flags & FLAG_REGION else None
        fixed = take("B", nv, 1) if flags & FLAG_FIXED else None
        return cls(xyz, tets, regions, fixed)

    @classmethod
    def load(cls, path):
        """Read a .qmesh file."""
        with open(path, "rb") as f:
            return cls.from_bytes(f.read())

    def save(self, path):
        """Write a .qmesh file."""
        with open(path, "wb") as f:
            f.write(self.to_bytes())

    def as_numpy(self):
        """(xyz (nv,3) float64, tets (nt,4) int32, regions or None, fixed or None)."""
        if _np is None:
            raise RuntimeError("numpy is not installed")
        reg = None if self.regions is None else _np.array(self.regions, dtype=_np.int32)
        fix = None if self.fixed is None else _np.array(self.fixed, dtype=_np.uint8)
        return (_np.array(self.xyz, dtype=_np.float64).reshape(-1, 3),
                _np.array(self.tets, dtype=_np.int32).reshape(-1, 4), reg, fix)


def _is_np(x):
    return _np is not None and isinstance(x, _np.ndarray)


def _save(path, data):
    """data to path: a file through a temporary file and os.replace (its
    permissions kept; a symbolic link stays one, the file it names is
    replaced); a pipe, a device or a process's descriptor (/dev/stdout,
    /dev/fd/N), which a replace would turn into a file, straight into."""
    path = os.fspath(path)
    target, direct = path, True
    try:
        proc = os.stat("/proc").st_dev
    except OSError:
        proc = None
    for _ in range(40):
        try:
            st = os.lstat(target)
        except FileNotFoundError:
            direct = target != path  # a link to nothing: open() creates its end
            break
        if not stat.S_ISLNK(st.st_mode):
            direct = not stat.S_ISREG(st.st_mode)
            break
        here = os.path.dirname(target) or "."
        if proc is not None and os.stat(here).st_dev == proc:
            break
        link = os.readlink(target)
        target = link if os.path.isabs(link) else os.path.join(here, link)
        if target.startswith("/proc/"):
            break
    if direct:
        with open(path, "wb") as f:
            f.write(data)
        return
    tmp = "%s.tmp%d" % (target, os.getpid())
    try:
        with open(tmp, "wb") as f:
            f.write(data)
            if os.path.exists(target):
                os.chmod(f.fileno(), stat.S_IMODE(os.stat(target).st_mode))
        os.replace(tmp, target)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _is_xdmf(path):
    """Whether path names an XDMF file (.xdmf or .xmf, as qdc takes both)."""
    return path.lower().endswith((".xdmf", ".xmf"))


def xdmf_h5_file(path):
    """The .h5 file an XDMF file at path keeps its heavy data in (its path,
    in the .xdmf's folder), or None if its data is inline. The rule is qdc's:
    every Format="HDF" DataItem reads "FILE.h5:/dataset", one FILE for all,
    relative, no "..". ValueError otherwise."""
    with open(path, "rb") as f:
        xml = f.read()
    try:
        root = _ET.fromstring(xml)
    except _ET.ParseError as e:
        raise ValueError("%s: not XML: %s" % (path, e)) from None
    files = set()
    for item in root.iter():
        if not str(item.tag).endswith("DataItem") or \
                (item.get("Format") or "").upper() != "HDF":
            continue
        ref = (item.text or "").strip()
        name = ref.split(":", 1)[0]
        if ":" not in ref or not name:
            raise ValueError("%s: an HDF DataItem without FILE.h5:/dataset: %r"
                             % (path, ref[:80]))
        files.add(name)
    if not files:
        return None
    if len(files) > 1:
        raise ValueError("%s: HDF data in %d files (%s): one .h5 file is read"
                         % (path, len(files), ", ".join(sorted(files))))
    name = files.pop()
    if os.path.isabs(name) or ".." in name.replace("\\", "/").split("/"):
        raise ValueError("%s: the .h5 file %s is not in the .xdmf's folder" % (path, name))
    return os.path.join(os.path.dirname(path), name)


def _form(parts):
    """(content type, body) of multipart/form-data: parts (name, file name,
    media type, bytes); the boundary found in none of them."""
    while True:
        b = "qdc" + uuid.uuid4().hex
        if not any(b.encode() in data for _, _, _, data in parts):
            break
    out = []
    for name, fname, ctype, data in parts:
        if any(ch in fname for ch in "\"\r\n"):
            raise ValueError("%s: a file name with a quote or line break" % fname)
        out.append(("--%s\r\nContent-Disposition: form-data; name=\"%s\"; filename=\"%s\"\r\n"
                    "Content-Type: %s\r\n\r\n" % (b, name, fname, ctype)).encode("utf-8"))
        out.extend([data, b"\r\n"])
    out.append(("--%s--\r\n" % b).encode())
    return "multipart/form-data; boundary=" + b, b"".join(out)


def _xdmf_renamed(xml, h5name):
    """The result's XML (naming result.h5) naming h5name instead."""
    if not h5name or any(ch in h5name for ch in "&<>\"':"):
        raise ValueError("%s cannot name an HDF5 file in XDMF (none of &<>\"': in it)" % h5name)
    return re.sub(rb"(>\s*)result\.h5:", lambda m: m.group(1) + h5name.encode("utf-8") + b":", xml)


def _job_id(job):
    jid = job["id"] if isinstance(job, dict) else str(job)
    return jid.rsplit("/", 1)[-1]


class Client:
    """A qdcd server. server defaults to $QDC_SERVER, else
    http://127.0.0.1:8080; token to $QDC_TOKEN. retries: further attempts
    after a 429, a 5xx or a connection failure."""

    def __init__(self, server=None, token=None, retries=8, timeout=120):
        self.server = (server or os.environ.get("QDC_SERVER") or "http://127.0.0.1:8080").rstrip("/")
        if "://" not in self.server:
            self.server = "http://" + self.server
        self.token = token if token is not None else os.environ.get("QDC_TOKEN")
        self.retries = retries
        self.timeout = timeout
        self.on_retry = lambda msg: print("qdc: " + msg, file=sys.stderr)

    # -- HTTP ---------------------------------------------------------------

    def _request(self, method, path, body=None, headers=None, timeout=None):
        """(status, headers, body bytes) of the first final answer."""
        url = self.server + path
        hdrs = dict(headers or {})
        if self.token:
            hdrs["Authorization"] = "Bearer " + self.token
        backoff = 0.5
        for attempt in range(self.retries + 1):
            req = urllib.request.Request(url, data=body, method=method, headers=hdrs)
            retry_after = None
            try:
                with urllib.request.urlopen(req, timeout=timeout or self.timeout) as resp:
                    return resp.status, resp.headers, resp.read()
            except urllib.error.HTTPError as e:
                data = e.read()
                if e.code != 429 and e.code < 500:
                    return e.code, e.headers, data
                err = "HTTP %d" % e.code
                retry_after = e.headers.get("Retry-After")
                if attempt == self.retries:
                    return e.code, e.headers, data
            except (urllib.error.URLError, OSError) as e:
                err = str(getattr(e, "reason", e))
                if attempt == self.retries:
                    raise QdcError(0, message="%s %s: %s" % (method, url, err)) from None
            wait = backoff * random.uniform(0.75, 1.25)
            if retry_after is not None:
                try:
                    wait = float(retry_after)
                except ValueError:
                    pass
            wait = min(wait, 30.0)
            backoff = min(backoff * 2, 30.0)
            if self.on_retry:
                self.on_retry("%s %s: %s; retrying in %.1f s" % (method, url, err, wait))
            time.sleep(wait)
        raise AssertionError("unreachable")

    def _json(self, method, path, body=None, headers=None, ok=(200,), timeout=None):
        status, _, data = self._request(method, path, body, headers, timeout)
        try:
            doc = json.loads(data.decode("utf-8")) if data else {}
        except ValueError:
            doc = {"title": "not JSON", "detail": data[:200].decode("utf-8", "replace")}
        if status not in ok:
            raise QdcError(status, doc)
        return doc

    # -- formats: the server's table (GET /v1/formats), read once ------------

    def formats(self):
        """The server's format table: {"formats": [{"name", "extension",
        "media_type", "upload", "result", "splice", ...}], "surfaces": [...]}."""
        if getattr(self, "_formats", None) is None:
            self._formats = self._json("GET", "/v1/formats")
        return self._formats

    def _by_ext(self, path, want):
        """The formats of path's extension (".msh": every Gmsh variant), in the
        table's order, of those with `want` ("upload" or "result") true;
        ValueError naming the extensions there are if none."""
        ext = os.path.splitext(os.fspath(path))[1].lower().lstrip(".")
        table = self.formats().get("formats", [])
        found = [f for f in table if f.get("extension") == ext and f.get(want)]
        if not found:
            exts = sorted({"." + f["extension"] for f in table if f.get(want)})
            raise ValueError("%s: use %s" % (path, ", ".join(exts)))
        return found

    # -- API ----------------------------------------------------------------

    def submit(self, mesh, options=None, idempotency_key=None, name=None, label=None):
        """New job. mesh: a path (of a format the server reads, by its
        extension: .mesh Medit, .msh Gmsh, .vtu... see formats(); sent as it
        is), a Mesh, or a tuple (xyz, tets[, regions[, fixed]]) of
        lists or numpy arrays.
        options: optimizer options, e.g. {"max_iter": 20, "boundary": "fixed"}.
        name: the job's file name (default: the path's last part; none for
        arrays); label: a text of the submitter's (at most 127 bytes). The
        job's "file_name" and "label" carry them.
        Returns the job (dict with "id", "state", ...)."""
        h5 = None
        if isinstance(mesh, (str, os.PathLike)):
            path = os.fspath(mesh)
            if name is None:
                name = os.path.basename(path)
            if _is_xdmf(path):
                h5 = xdmf_h5_file(path)
            if h5 is None:
                first = self._by_ext(path, "upload")[0]  # qdcd records the variant read
                ctype, named = first.get("media_type"), None
                if ctype is None:  # no media type: named in the query
                    ctype, named = "application/octet-stream", first["name"]
            with open(path, "rb") as f:
                body = f.read()
            if h5 is not None:  # the .xdmf and its .h5 in one request
                with open(h5, "rb") as f:
                    h5data = f.read()
                named = None
                ctype, body = _form([("xdmf", os.path.basename(path), "application/xml", body),
                                     ("h5", os.path.basename(h5), "application/x-hdf5", h5data)])
        else:
            if not isinstance(mesh, Mesh):
                mesh = Mesh(*mesh)
            ctype, named, body = MEDIA_QMESH, None, mesh.to_bytes()
        params = {k: (("on" if v else "off") if isinstance(v, bool) else v)
                  for k, v in (options or {}).items()}
        if named:
            params["format"] = named
        if name:
            params["name"] = name
        if label:
            params["label"] = label
        query = "?" + urllib.parse.urlencode(params) if params else ""
        key = idempotency_key or uuid.uuid4().hex
        return self._json("POST", "/v1/jobs" + query, body,
                          {"Content-Type": ctype, "Idempotency-Key": key}, ok=(202,))

    def job(self, job):
        """The job's current JSON (state, done, iterations, latest progress)."""
        return self._json("GET", "/v1/jobs/" + _job_id(job))

    def jobs(self):
        """Every job visible to this token (all pages)."""
        out, token = [], None
        while True:
            q = "?page_size=200" + ("&page_token=" + token if token else "")
            page = self._json("GET", "/v1/jobs" + q)
            out.extend(page.get("jobs", []))
            token = page.get("next_page_token")
            if not token:
                return out

    def progress(self, job, after=-1, wait=30, attempt=None):
        """One long-poll: records after seq `after` (waits up to `wait` s).
        attempt: the run the records up to `after` came from; if the job has
        run again since, the reply starts over with the new run's records and
        says "restarted"."""
        q = "after=%d&wait=%g" % (after, wait) + ("&attempt=%d" % attempt if attempt else "")
        return self._json("GET", "/v1/jobs/%s/progress?%s" % (_job_id(job), q), timeout=wait + 30)

    def wait(self, job, on_progress=None, poll_wait=30, raise_on_failure=True, on_restart=None,
             after=-1, attempt=None):
        """Follow the job until it ends; on_progress(record) is called once per
        iteration record, in order. A job that runs again (its server died)
        starts its records over: on_restart({"from_attempt": A, "attempt": B})
        is called first. after, attempt: resume after the records already seen
        (their seq and attempt). Returns the final job JSON; raises JobFailed
        if it failed or was cancelled (unless raise_on_failure is False)."""
        while True:
            p = self.progress(job, after, poll_wait, attempt)
            if p.get("restarted") and on_restart:
                on_restart(p["restarted"])
            for rec in p.get("records", []):
                if on_progress:
                    on_progress(rec)
            after = p.get("next_after", after)
            attempt = p.get("attempt") or attempt
            if p.get("done"):
                break
        final = self.job(job)
        if raise_on_failure and final.get("state") != "succeeded":
            raise JobFailed(final)
        return final

    def result(self, job, path=None, fmt=None):
        """The optimized mesh. Without path: a Mesh (downloaded as binary).
        With path: written there, format from fmt ('medit', 'gmsh', 'vtu',
        ...) or the extension (the job's own variant when the extension names
        its family: then the upload comes back with only the coordinates
        replaced; a job with options {"topology": "flips"} has other tets, and
        its result is written by qdc's own writer in every format). A job
        sent as an .xdmf with its .h5 file (its record says "h5": true),
        written to a .xdmf or .xmf path, comes back as two files: the .h5
        beside it (out.xdmf: out.h5) and the .xdmf naming it. Returns path."""
        jid = _job_id(job)
        if path is not None and fmt is None and _is_xdmf(os.fspath(path)):
            if self.job(jid).get("mesh", {}).get("h5"):  # an XDMF+HDF5 job
                return self._xdmf_h5_result(jid, os.fspath(path))
        if path is None:
            fmt = "qmesh"
        elif fmt is None:
            family = self._by_ext(path, "upload")
            fmt = family[0]["name"]
            own = self.job(jid).get("mesh", {}).get("format")
            if own in [f["name"] for f in family]:
                fmt = own  # the upload written back
        status, _, data = self._request("GET", "/v1/jobs/%s/result?format=%s" % (jid, fmt))
        if status != 200:
            raise QdcError(status, _problem(data))
        if path is None:
            return Mesh.from_bytes(data)
        _save(path, data)
        return path

    def _xdmf_h5_result(self, jid, path):
        """path (.xdmf) and the .h5 beside it of an XDMF+HDF5 job."""
        h5path = os.path.splitext(path)[0] + ".h5"
        status, _, h5data = self._request("GET", "/v1/jobs/%s/result?format=h5" % jid)
        if status != 200:
            raise QdcError(status, _problem(h5data))
        status, _, xml = self._request("GET", "/v1/jobs/%s/result?format=xdmf" % jid)
        if status != 200:
            raise QdcError(status, _problem(xml))
        xml = _xdmf_renamed(xml, os.path.basename(h5path))
        _save(h5path, h5data)  # the .h5 first: the .xdmf names it
        _save(path, xml)
        return path

    def report(self, job, path=None):
        """The quality/boundary-error report (dict); also written to path if given."""
        status, _, data = self._request("GET", "/v1/jobs/%s/report" % _job_id(job))
        if status != 200:
            raise QdcError(status, _problem(data))
        if path is not None:
            with open(path, "wb") as f:
                f.write(data)
        return json.loads(data.decode("utf-8"))

    def outcome(self, job):
        """The outcome in words of a finished job (its report's "outcome":
        summary, left_bad, boundary, warnings, suggestions); outcome_lines()
        prints it as qdc does."""
        return self.report(job).get("outcome", {})

    def cancel(self, job):
        return self._json("POST", "/v1/jobs/%s:cancel" % _job_id(job))

    def delete(self, job):
        self._json("DELETE", "/v1/jobs/" + _job_id(job), ok=(204,))


def _problem(data):
    try:
        return json.loads(data.decode("utf-8"))
    except ValueError:
        return {}


def outcome_lines(report):
    """The outcome in words of a report (dict), as `qdc optimize` ends: "outcome:
    ...", then "warning: ..." and "suggestion: ..." lines. The texts are the
    report's (computed by the library, docs/defaults.md); none are made here."""
    o = report.get("outcome") or {}
    if not o.get("summary"):
        return []
    return (["outcome: " + o["summary"]] + ["warning: " + w for w in o.get("warnings", [])]
            + ["suggestion: " + t for t in o.get("suggestions", [])])


# -- command line -------------------------------------------------------------

def _line(rec):
    return "%-6s %3d  q mean %.4f min %+.4f  inverted %d  %.1fs" % (
        rec.get("phase", "?"), rec.get("iteration", 0), rec.get("mean_ratio_mean", 0),
        rec.get("mean_ratio_min", 0), rec.get("n_inverted", 0), rec.get("elapsed", 0))


def _print_outcome(report):
    for line in outcome_lines(report):
        print("qdc: " + line, file=sys.stderr)


def main(argv=None):
    import argparse

    ap = argparse.ArgumentParser(prog="qdc_client.py", description="qdcd client")
    ap.add_argument("--server", help="default $QDC_SERVER, else http://127.0.0.1:8080")
    ap.add_argument("--token", help="default $QDC_TOKEN")
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("submit", help="new job; prints its id; -o/--report wait for it")
    s.add_argument("mesh")
    s.add_argument("-o", "--output")
    s.add_argument("--report")
    s.add_argument("--wait", action="store_true")
    s.add_argument("--label", help="a label for the job (shown with its file name)")
    s.add_argument("--name", help="the job's file name (default: IN's last part)")
    s.add_argument("--opt", action="append", default=[], metavar="NAME=VALUE",
                   help="optimizer option, e.g. max_iter=20 (repeatable)")
    f = sub.add_parser("fetch", help="download a finished job's result and/or report")
    f.add_argument("job")
    f.add_argument("-o", "--output")
    f.add_argument("--report")
    for name in ("status", "cancel"):
        sub.add_parser(name).add_argument("job")
    sub.add_parser("jobs")
    a = ap.parse_args(argv)
    c = Client(a.server, a.token)
    try:
        if a.cmd == "submit":
            opts = dict(o.split("=", 1) for o in a.opt)
            job = c.submit(a.mesh, opts, name=a.name, label=a.label)
            print(job["id"], flush=True)
            if a.wait or a.output or a.report:
                c.wait(job, on_progress=lambda r: print(_line(r), file=sys.stderr, flush=True))
                if a.output:
                    c.result(job, a.output)
                _print_outcome(c.report(job, a.report))
        elif a.cmd == "fetch":
            if a.output:
                c.result(a.job, a.output)
            _print_outcome(c.report(a.job, a.report))
        elif a.cmd == "status":
            print(json.dumps(c.job(a.job), indent=1))
        elif a.cmd == "cancel":
            print(c.cancel(a.job)["state"])
        else:
            for j in c.jobs():
                names = j.get("label", "") + (" (%s)" % j["file_name"] if j.get("label") and
                                              j.get("file_name") else j.get("file_name", ""))
                print(j["id"], j["state"], names) if names else print(j["id"], j["state"])
    except JobFailed as e:
        print("qdc: %s" % e, file=sys.stderr)
        return 11
    except QdcError as e:
        print("qdc: %s" % e, file=sys.stderr)
        return 12 if e.status == 0 or e.status >= 500 or e.status == 429 else 10
    except (OSError, ValueError) as e:
        print("qdc: %s" % e, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
