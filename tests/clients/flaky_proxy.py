"""flaky_proxy.py - an HTTP proxy in front of qdcd that loses answers, for
tests/clients/lost.sh. Usage: flaky_proxy.py UPSTREAM_PORT PORT_FILE LOG MODE

Every request is forwarded to 127.0.0.1:UPSTREAM_PORT. The first POST /v1/jobs
is forwarded too, but its answer is lost: MODE 503 answers 503 + Retry-After: 1
instead, MODE drop closes the connection without a word. Each request line
and its Idempotency-Key go to LOG."""
import http.client
import http.server
import sys

UP, PORT_FILE, LOG, MODE = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4]
lost = False


class Proxy(http.server.BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"

    def log_message(self, *args):
        pass

    def forward(self):
        global lost
        n = int(self.headers.get("Content-Length") or 0)
        body = self.rfile.read(n) if n else None
        with open(LOG, "a") as f:
            f.write("%s %s %s\n" % (self.command, self.path, self.headers.get("Idempotency-Key", "-")))
        hdrs = {k: v for k, v in self.headers.items() if k.lower() not in ("host", "expect")}
        c = http.client.HTTPConnection("127.0.0.1", UP, timeout=120)
        c.request(self.command, self.path, body=body, headers=hdrs)
        r = c.getresponse()
        data = r.read()
        if self.command == "POST" and self.path.startswith("/v1/jobs") and not lost:
            lost = True  # the job exists upstream now; its answer never arrives
            if MODE == "drop":
                self.close_connection = True
                self.wfile.flush()
                self.connection.shutdown(2)
                return
            self.send_response(503)
            self.send_header("Retry-After", "1")
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        self.send_response(r.status)
        for k, v in r.getheaders():
            if k.lower() not in ("transfer-encoding", "connection", "content-length"):
                self.send_header(k, v)
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data)

    do_GET = do_POST = do_DELETE = forward

    def handle_expect_100(self):
        self.send_response_only(100)
        self.end_headers()
        return True


srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Proxy)
with open(PORT_FILE + ".tmp", "w") as f:
    f.write(str(srv.server_address[1]))
import os  # noqa: E402
os.rename(PORT_FILE + ".tmp", PORT_FILE)
srv.serve_forever()
