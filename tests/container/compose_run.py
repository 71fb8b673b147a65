#!/usr/bin/python3
"""compose_run.py - docker/compose.yaml as plain `ENGINE run` commands, for a
machine without a compose tool whose tests may only use loopback addresses.

  compose_run.py COMPOSE.yaml ENGINE PREFIX PORTS IMAGES [EXTRA]

Prints one line per service, in compose's start order (depends_on first):
  SERVICE<TAB>shell-quoted `ENGINE run -d ...` command
Each service runs as in COMPOSE.yaml (its image, command, environment,
volumes, stop signal) with these changes, and only these:
  - every container on the host network (--network host) instead of compose's
    bridge networks, so each service gets its own loopback port: PORTS is
    "svc=port,svc=port,..."; a service's own address 0.0.0.0:N becomes
    127.0.0.1:PORT(svc), another service's name svc:N becomes 127.0.0.1:PORT(svc),
    and PGPORT=PORT(svc) is set for a service that has no such address (the
    database: its entrypoint listens on $PGPORT);
  - the container is named PREFIX-svc, with hostname svc; a named volume V
    becomes PREFIX-V;
  - the images are the test's own tags: IMAGES is "dockerfile=tag,..." keyed by
    each service's build dockerfile's file name;
  - ${VAR:-default} in the file is expanded from the environment;
  - EXTRA ("svc=arg arg...;svc=...") appends arguments to a service's command
    (the test's shorter lease, the database's loopback-only listen_addresses);
    for qdcd a later option overrides an earlier one.
No health check is run by the engine (--no-healthcheck with podman: it needs
systemd timers); the test waits for each service itself, as depends_on says.
"""
import os
import re
import shlex
import sys

import yaml


def expand(s):
    def one(m):
        name, default = m.group(1), m.group(3)
        v = os.environ.get(name)
        return v if v else (default or "")
    return re.sub(r"\$\{([A-Za-z_][A-Za-z0-9_]*)(:-([^}]*))?\}", one, s)


def order(services):
    done, out = set(), []

    def visit(n, stack=()):
        if n in done:
            return
        if n in stack:
            sys.exit("compose_run: depends_on cycle at " + n)
        deps = services[n].get("depends_on", [])
        for d in (deps if isinstance(deps, list) else list(deps)):
            visit(d, stack + (n,))
        done.add(n)
        out.append(n)

    for n in services:
        visit(n)
    return out


def main():
    path, engine, prefix, ports, images = sys.argv[1:6]
    extra = sys.argv[6] if len(sys.argv) > 6 else ""
    port = dict(p.split("=") for p in ports.split(",") if p)
    image = dict(i.split("=") for i in images.split(",") if i)
    more = {}
    for e in extra.split(";"):
        if e.strip():
            k, v = e.split("=", 1)
            more[k.strip()] = shlex.split(v)
    svcs = yaml.safe_load(open(path))["services"]
    names = sorted(svcs, key=len, reverse=True)  # qdcd10 before qdcd1

    def local(svc, s):
        s = expand(str(s))
        s = re.sub(r"\b0\.0\.0\.0:\d+", "127.0.0.1:" + port[svc], s)
        for n in names:
            s = re.sub(r"(?<![\w.-])" + re.escape(n) + r":\d+\b", "127.0.0.1:" + port[n], s)
        return s

    for svc in order(svcs):
        d = svcs[svc]
        if svc not in port:
            sys.exit("compose_run: no port for service " + svc)
        df = os.path.basename(d["build"]["dockerfile"])
        if df not in image:
            sys.exit("compose_run: no image for " + df)
        cmd = [engine, "run", "-d", "--name", prefix + "-" + svc, "--hostname", svc,
               "--network", "host"]
        if engine == "podman":
            cmd.append("--no-healthcheck")
        if d.get("stop_signal"):
            cmd += ["--stop-signal", d["stop_signal"]]
        env = d.get("environment", {}) or {}
        if isinstance(env, list):
            env = dict(e.split("=", 1) for e in env)
        args = [local(svc, a) for a in d.get("command", []) or []]
        own = any("127.0.0.1:" + port[svc] in x for x in args + [local(svc, v) for v in env.values()])
        if not own:
            cmd += ["-e", "PGPORT=" + port[svc]]
        for k, v in env.items():
            cmd += ["-e", k + "=" + local(svc, v)]
        for v in d.get("volumes", []) or []:
            src, dst = v.split(":", 1)
            cmd += ["-v", (prefix + "-" + src if not src.startswith((".", "/")) else src) + ":" + dst]
        cmd.append(image[df])
        cmd += args + more.get(svc, [])
        print(svc + "\t" + " ".join(shlex.quote(c) for c in cmd))


if __name__ == "__main__":
    main()
