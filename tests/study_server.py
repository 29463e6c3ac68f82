#!/usr/bin/python3
"""`sirl study serve` over HTTP (ctest): answers are committed at once; every bad request (wrong
token, another participant, malformed, duplicate, out of order) gets 400/403 and changes
nothing; after kill -9 and a restart the study resumes at the next unanswered query.
With STUDY_BROWSER=1 it also drives the real page in Debian's chromium (playwright-core)."""
import hashlib
import json
import os
import re
import resource
import signal
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.parse
import urllib.request

import h5py

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402
from sirl_testing import run_sirl  # noqa: E402

SIRL = sirl_testing.sirl_binary()
SRC = sirl_testing.source_dir()


def serve(study, participant, port=0, n_sim=3, n_pref=2, file_size_limit=None):
    """Starts a server (port 0: the OS picks a free one, no check-then-bind race) and returns it
    with its URL and the participant's token once it prints the URL: the socket is listening by
    then, so requests queue until the accept loop runs. `file_size_limit` (bytes) makes every
    write past it fail with EFBIG, as a full disk fails with ENOSPC."""
    def limit():
        if file_size_limit is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (file_size_limit, file_size_limit))
    p = subprocess.Popen([SIRL, "study", "serve", "--env", "grid", "--participant", participant,
                          "--similarity", str(n_sim), "--preference", str(n_pref), "--practice", "1",
                          "--scenario", "Keep away from the laptop.", "--scenario-features",
                          "laptop_distance", "--out", study, "--port", str(port)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         stdin=subprocess.DEVNULL, preexec_fn=limit)
    url = None
    for _ in range(2):
        line = p.stdout.readline()
        if line.startswith("open: "):
            url = line.split("open: ")[1].strip()
            break
    if not url:
        p.kill()
        sys.exit(f"FAIL: server did not start: {p.stderr.read()}")
    qs = urllib.parse.parse_qs(urllib.parse.urlparse(url).query)
    return p, url, qs["t"][0]


def http(method, url, data=None):
    body = urllib.parse.urlencode(data).encode() if data is not None else None
    try:
        with urllib.request.urlopen(urllib.request.Request(url, data=body, method=method), timeout=10) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.read().decode()


def browse_to_the_end(tmp, web, env, who, scenario, view):
    """Serves `who` 2 similarity and 1 preference queries on `env` (a 200-trajectory space) and
    has chromium answer them through the page in `view`; every answer must be in the file."""
    study = os.path.join(tmp, env + ".h5")
    server = subprocess.Popen([SIRL, "study", "serve", "--env", env, "--trajectories", "200",
                               "--participant", who, "--similarity", "2", "--preference", "1",
                               "--practice", "1", "--scenario", scenario, "--out", study,
                               "--port", "0"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              stdin=subprocess.DEVNULL)
    line = ""
    while not line.startswith("open: "):
        line = server.stdout.readline()
        if not line:
            sys.exit(f"FAIL: {env} server did not start: {server.stderr.read()}")
    p = subprocess.run(["node", os.path.join(SRC, "tests", "study_browser.mjs"),
                        line.split("open: ")[1].strip(), view], cwd=web, capture_output=True,
                       text=True, timeout=300)
    server.kill()
    if p.returncode != 0:
        sys.exit(f"FAIL: {env} browser test\n{p.stdout}\n{p.stderr}")
    with h5py.File(study, "r") as f:
        g = f[f"study/participants/{who}"]
        assert len(g["similarity_answer"]) == 2 and len(g["preference_answer"]) == 1
    print(p.stdout.strip())


def answers(study, who):
    with h5py.File(study, "r") as f:
        g = f[f"study/participants/{who}"]
        return (list(g["similarity_answer"][:]), list(g["preference_answer"][:]),
                list(g["similarity_ms"][:]), list(g["similarity_time"][:]))


with tempfile.TemporaryDirectory() as tmp:
    study = os.path.join(tmp, "study.h5")
    srv, url, token = serve(study, "alice")
    port = urllib.parse.urlparse(url).port
    assert port, url
    base = f"http://127.0.0.1:{port}"
    assert url.startswith(f"http://127.0.0.1:{port}/?p=alice&t="), url
    # A second server on the busy port must refuse to start (no SO_REUSEPORT: two servers would
    # split one participant's requests between them).
    second = run_sirl("study", "serve", "--env", "grid", "--participant", "bob",
                      "--scenario", "Keep away from the laptop.", "--scenario-features",
                      "laptop_distance", "--out", study + ".other.h5", "--port", str(port),
                      timeout=30)
    assert second.returncode == 2 and "cannot listen" in second.stderr, (second.returncode,
                                                                         second.stderr)
    print("ok: a second server on a busy port is refused:", second.stderr.strip())
    st, body = http("GET", f"{base}/api/state?p=alice&t={token}")
    assert st == 200 and '"stage":"similarity"' in body and '"index":0' in body, body
    st, page = http("GET", base + "/")
    assert st == 200 and "study.js" in page
    print("ok: the page and the state API answer")

    def post(**kw):
        d = dict(p="alice", t=token, kind="similarity", index=0, answer=2, response_ms=1234)
        d.update(kw)
        d = {k: v for k, v in d.items() if v is not None}
        return http("POST", f"{base}/api/answer", d)

    bad = [
        (dict(t="wrong"), 403, "token"),
        (dict(kind="opinion"), 400, "kind"),
        (dict(answer=7), 400, "odd one out"),
        (dict(answer="two"), 400, "numbers"),
        (dict(index=None), 400, "missing field 'index'"),
        (dict(index=1), 400, "out of order"),
        (dict(index=99), 400, "does not exist"),
        (dict(response_ms=-5), 400, "response_ms"),
        (dict(kind="preference", answer=1), 400, "after the similarity"),
    ]
    for kw, code, words in bad:
        st, body = post(**kw)
        assert st == code and words in body, (kw, st, body)
        assert answers(study, "alice")[0] == [], f"{kw} wrote something"
    print(f"ok: {len(bad)} bad requests refused with 400/403, nothing written")

    st, body = post()
    assert st == 200 and '"index":1' in body, body
    st, body = post()
    assert st == 400 and "already answered" in body, body
    st, _ = post(index=1, answer=0, response_ms=800)
    assert st == 200
    sim, pref, ms, when = answers(study, "alice")
    assert sim == [2, 0] and ms == [1234.0, 800.0] and all(t > 1.6e9 for t in when), (sim, ms, when)
    print("ok: answers committed at once with response time and timestamp; duplicates refused")

    # One server per study file: each rewrites the whole file from its memory, so a second one
    # (another participant, same file) must be refused while the first runs.
    second = run_sirl("study", "serve", "--env", "grid", "--participant", "bob",
                      "--scenario", "Stay low.", "--out", study, "--port", "0", timeout=30)
    assert second.returncode == 2 and "in use by sirl study serve" in second.stderr, \
        second.stderr
    with h5py.File(study, "r") as f:
        assert "bob" not in f["study/participants"], "the refused server wrote to the file"
    print("ok: a second server on the same study file is refused:", second.stderr.strip())

    # kill -9; bob takes his turn on the same file; alice's server restarts and resumes at her
    # similarity query 2 with both participants in the file.
    srv.send_signal(signal.SIGKILL)
    srv.wait()
    srv_b, _, token_b = serve(study, "bob")
    srv_b.send_signal(signal.SIGTERM)
    srv_b.wait()
    srv, url, token2 = serve(study, "alice", port)
    assert token2 == token, "the participant keeps their token (and URL) across restarts"
    st, body = http("GET", f"{base}/api/state?p=alice&t={token}")
    nxt = json.loads(body)["next"] if st == 200 else None
    assert nxt and nxt["kind"] == "similarity" and nxt["index"] == 2, body
    assert answers(study, "alice")[0] == [2, 0]
    print("ok: after kill -9 and restart the study resumes at the next unanswered query")

    # bob's valid token, in the same file, on alice's server: this server records alice only.
    st, body = http("POST", f"{base}/api/answer",
                    dict(p="bob", t=token_b, kind="similarity", index=0, answer=1, response_ms=1))
    assert st == 403 and "records participant alice only" in body, body
    assert answers(study, "bob")[0] == [], "bob's answer written through alice's server"
    # Strict numbers: each of these used to be read as something else.
    for kw, words in [(dict(index="1e0"), "index must be"), (dict(index="-1"), "index must be"),
                      (dict(index=" 2"), "index must be"), (dict(answer="0x1"), "decimal"),
                      (dict(answer="1abc"), "decimal"), (dict(response_ms="nan"), "decimal")]:
        d = dict(p="alice", t=token, kind="similarity", index=2, answer=1, response_ms=5)
        d.update(kw)
        st, body = http("POST", f"{base}/api/answer", d)
        assert st == 400 and words in body, (kw, st, body)
    for bad_id in ("5abc", "1e3", "-1", ""):
        st, body = http("GET", f"{base}/api/trajectory?p=alice&t={token}&id={bad_id}")
        assert st == 400, (bad_id, st, body)
    # A body over 64 KiB is refused (413) without being read; nothing is written.
    big = urllib.request.Request(f"{base}/api/answer", data=b"x" * (200 * 1024), method="POST")
    try:
        urllib.request.urlopen(big, timeout=10)
        st = 200
    except urllib.error.HTTPError as e:
        st = e.code
    except (ConnectionError, urllib.error.URLError):
        st = 413  # the server may close before the client finished sending
    assert st == 413, st
    assert answers(study, "alice")[0] == [2, 0]
    print("ok: strict numbers, a 200 KiB body refused with 413, nothing written")

    # Raw requests through the server's own socket path. A chunked upload of 100 MB (1600 chunks
    # of 64 KiB, no token) is refused past 64 KiB: the server's resident memory stays within a few
    # MB of what it was (cpp-httplib alone buffers a chunked body whole before any handler).
    import socket

    def rss_kib(pid):
        for line in open(f"/proc/{pid}/status"):
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
        return 0

    def raw(head, body_chunks=(), read=True):
        c = socket.create_connection(("127.0.0.1", port), timeout=10)
        c.sendall(head)
        sent = 0
        try:
            for ch in body_chunks:
                c.sendall(ch)
                sent += 1
        except OSError:
            pass  # the server closed after refusing: the rest is never read
        reply = b""
        if read:
            try:
                while b"\r\n\r\n" not in reply:
                    part = c.recv(65536)
                    if not part:
                        break
                    reply += part
            except OSError:
                pass
        c.close()
        return reply, sent

    before = rss_kib(srv.pid)
    chunk = b"10000\r\n" + b"x" * 0x10000 + b"\r\n"
    reply, sent = raw(b"POST /api/answer HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n"
                      b"Content-Type: application/x-www-form-urlencoded\r\n\r\n",
                      (chunk for _ in range(1600)))
    after = rss_kib(srv.pid)
    assert reply.startswith(b"HTTP/1.1 413"), reply[:200]
    assert after - before < 8 * 1024, f"resident memory grew {after - before} KiB"
    print(f"ok: a chunked 100 MB upload refused with 413 after {sent} chunks sent; resident "
          f"memory {before} → {after} KiB")
    # Framing headers two readers could disagree on: 400, whatever the body.
    for head in (b"Content-Length: 5\r\nContent-Length: 7\r\n", b"Content-Length: 0x10\r\n",
                 b"Content-Length: +5\r\n", b"Content-Length: 5\r\nTransfer-Encoding: chunked\r\n"):
        reply, _ = raw(b"POST /api/answer HTTP/1.1\r\nHost: x\r\n" + head + b"\r\nindex=0")
        assert reply.startswith(b"HTTP/1.1 400"), (head, reply[:200])
    # A chunked answer within the limit is an answer like any other.
    form = urllib.parse.urlencode(dict(p="alice", t=token, kind="similarity", index=2, answer=0,
                                       response_ms=5)).encode()
    reply, _ = raw(b"POST /api/answer HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n"
                   b"Content-Type: application/x-www-form-urlencoded\r\n\r\n"
                   + b"%x\r\n" % len(form) + form + b"\r\n0\r\n\r\n")
    assert reply.startswith(b"HTTP/1.1 200"), reply[:300]
    assert answers(study, "alice")[0] == [2, 0, 0], answers(study, "alice")[0]
    print("ok: duplicate, non-decimal and conflicting Content-Length refused (400); a chunked "
          "answer within 64 KiB accepted")

    # Every other path is bounded too: a chunked 100 MB upload to a path that takes no body, with
    # no token, is refused before it is read (cpp-httplib alone reads it whole before the 404).
    before = rss_kib(srv.pid)
    for line in (b"POST /nope", b"POST /api/state", b"PUT /api/answer", b"GET /api/state"):
        reply, sent = raw(line + b" HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n",
                          (chunk for _ in range(1600)))
        assert reply.startswith(b"HTTP/1.1 413"), (line, reply[:200])
    reply, _ = raw(b"GET /nope HTTP/1.1\r\nHost: x\r\nContent-Length: 99999999\r\n\r\n",
                   (chunk for _ in range(100)))
    assert reply.startswith(b"HTTP/1.1 413"), reply[:200]
    # A body-carrying method without a length would be read until the client closes: 411.
    reply, _ = raw(b"POST /api/answer HTTP/1.1\r\nHost: x\r\n\r\n", (chunk for _ in range(100)))
    assert reply.startswith(b"HTTP/1.1 411"), reply[:200]
    reply, _ = raw(b"DELETE /nope HTTP/1.1\r\nHost: x\r\n\r\n", (chunk for _ in range(100)))
    assert reply.startswith(b"HTTP/1.1 411"), reply[:200]
    after = rss_kib(srv.pid)
    # 400 MB were sent at these paths: buffering any one of them would add 100 MB. The bound
    # leaves room for the worker threads' stacks and ThreadSanitizer's shadow memory.
    assert after - before < 32 * 1024, f"resident memory grew {after - before} KiB"
    # A refused request's connection is closed: what the client sends after the refusal is never
    # parsed as a request (cpp-httplib kept reading after answering "Connection: close").
    for head in (b"POST /nope HTTP/1.1\r\nHost: x\r\nContent-Length: 3\r\n\r\n",
                 b"POST /api/answer HTTP/1.1\r\nHost: x\r\n\r\n"):
        c = socket.create_connection(("127.0.0.1", port), timeout=10)
        c.sendall(head)
        got = c.recv(65536)
        assert got.startswith(b"HTTP/1.1 41"), got[:200]
        time.sleep(0.1)
        try:
            c.sendall(b"GET /api/state HTTP/1.1\r\nHost: x\r\n\r\n")
            while part := c.recv(65536):
                got += part
        except OSError:
            pass  # closed: the second request never reached a parser
        c.close()
        assert got.count(b"HTTP/1.1 ") == 1, (head, got[:400])
    # A GET without a body is still served.
    st, _ = http("GET", f"{base}/api/state?p=alice&t={token}")
    assert st == 200, st
    print(f"ok: bodies to other paths refused (413) and bodies without a length (411); resident "
          f"memory {before} → {after} KiB")

    # Slow and idle clients cannot starve a participant: 64 connections trickling one header line
    # per 0.5 s and 200 connected but silent ones, then a real request must be answered in < 2 s.
    import threading
    import time
    stop = threading.Event()
    slow, idle = [], []
    for _ in range(64):
        c = socket.create_connection(("127.0.0.1", port), timeout=5)
        c.sendall(b"GET /api/state HTTP/1.1\r\nHost: x\r\n")
        slow.append(c)
    for _ in range(200):
        idle.append(socket.create_connection(("127.0.0.1", port), timeout=5))

    def trickle():
        while not stop.is_set():
            for c in slow:
                try:
                    c.sendall(b"X-Slow: 1\r\n")
                except OSError:
                    pass
            time.sleep(0.5)
    t = threading.Thread(target=trickle, daemon=True)
    t.start()
    time.sleep(0.5)
    t0 = time.time()
    st, body = http("GET", f"{base}/api/state?p=alice&t={token}")
    took = time.time() - t0
    stop.set()
    for c in slow + idle:
        c.close()
    assert st == 200 and took < 2.0, (st, took)
    print(f"ok: with 64 slow and 200 idle connections open a request was answered in {took:.2f} s")

    # --host is checked before anything is written; a non-loopback host is served with a warning
    # and a working URL.
    fresh = os.path.join(tmp, "host.h5")
    for bad_host in ("", "not a host", "999.1.1.1"):
        q = run_sirl("study", "serve", "--env", "grid", "--participant", "dan",
                     "--scenario", "x", "--out", fresh, "--host", bad_host, "--port", "0",
                     timeout=30)
        assert q.returncode == 2 and "--host" in q.stderr, (bad_host, q.returncode, q.stderr)
        assert not os.path.exists(fresh), f"--host {bad_host!r} wrote the study file"
    pa = subprocess.Popen([SIRL, "study", "serve", "--env", "grid", "--participant", "dan",
                           "--scenario", "x", "--out", fresh, "--host", "0.0.0.0",
                           "--port", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, stdin=subprocess.DEVNULL)
    line = ""
    for _ in range(2):
        line = pa.stdout.readline()
        if line.startswith("open: "):
            break
    pa.terminate()
    err = pa.communicate(timeout=30)[1]
    assert re.match(r"open: http://127\.0\.0\.1:[1-9]\d*/\?p=dan&t=", line), line
    assert "WARNING" in err and "not a loopback address" in err, err
    print("ok: bad --host values refused before writing; 0.0.0.0 warns and prints a working URL")
    # A SIGTERM sent the moment the URL is printed (before the listen loop has begun) still
    # stops the server: repeated, since the window is short.
    for i in range(12):
        pq = subprocess.Popen([SIRL, "study", "serve", "--env", "grid", "--participant", "dan",
                               "--scenario", "x", "--out", fresh, "--port", "0"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              stdin=subprocess.DEVNULL)
        for _ in range(2):
            if pq.stdout.readline().startswith("open: "):
                break
        pq.terminate()
        try:
            err = pq.communicate(timeout=15)[1]
        except subprocess.TimeoutExpired:
            pq.kill()
            raise AssertionError(f"try {i}: a SIGTERM right after the URL did not stop the server")
        assert "stopped (SIGTERM)" in err, err
    print("ok: a SIGTERM right after the URL is printed stops the server (12 of 12)")
    st, body = http("GET", f"{base}/api/trajectory?p=alice&t={token}&id=5")
    assert st == 200, body
    # GridRobot: 9 cells of a corner-to-corner path of unit moves, and an end angle in 30° steps.
    tr = json.loads(body)
    pts = tr["points"]
    assert len(pts) == 9 and all(len(q) == 2 and 0 <= q[0] <= 4 and 0 <= q[1] <= 4 for q in pts), tr
    assert all(abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1 for a, b in zip(pts, pts[1:])), tr
    assert tr["angle"] in (-90, -60, -30, 0, 30, 60, 90), tr
    assert [o["name"] for o in tr["objects"]] == ["obstacle1", "obstacle2", "laptop"], tr
    st, body = http("GET", f"{base}/api/trajectory?p=alice&t={token}&id=999999")
    assert st == 400, body
    print("ok: another participant's token is refused; trajectory API checks its id")

    # A full disk while serving: the answer is refused with 500 and the cause, the server keeps
    # running, the study file is untouched and no temporary file is left; once there is room
    # (restarted without the limit) the same query is asked again and accepted.
    full = os.path.join(tmp, "full", "study.h5")
    os.mkdir(os.path.dirname(full))
    srv_e, url_e, token_e = serve(full, "erin")
    base_e = f"http://127.0.0.1:{urllib.parse.urlparse(url_e).port}"
    erin = dict(p="erin", t=token_e, kind="similarity", response_ms=700)
    st, _ = http("POST", f"{base_e}/api/answer", dict(erin, index=0, answer=1))
    assert st == 200
    srv_e.terminate()
    srv_e.wait()
    with open(full, "rb") as f:
        before = hashlib.sha256(f.read()).hexdigest()
    srv_e, url_e, _ = serve(full, "erin", file_size_limit=os.path.getsize(full) // 2)
    base_e = f"http://127.0.0.1:{urllib.parse.urlparse(url_e).port}"
    st, body = http("POST", f"{base_e}/api/answer", dict(erin, index=1, answer=2))
    refused = json.loads(body)["error"] if st == 500 else body
    assert st == 500 and "could not save the answer" in body and "File too large" in body, \
        (st, body)
    st, body = http("GET", f"{base_e}/api/state?p=erin&t={token_e}")
    assert st == 200 and json.loads(body)["next"]["index"] == 1, (st, body)
    assert srv_e.poll() is None, "the server died on a full disk"
    with open(full, "rb") as f:
        assert hashlib.sha256(f.read()).hexdigest() == before, "a failed save changed the file"
    assert sorted(os.listdir(os.path.dirname(full))) == ["study.h5", "study.h5.lock"], \
        os.listdir(os.path.dirname(full))
    srv_e.terminate()
    srv_e.wait()
    srv_e, url_e, _ = serve(full, "erin")
    base_e = f"http://127.0.0.1:{urllib.parse.urlparse(url_e).port}"
    st, body = http("POST", f"{base_e}/api/answer", dict(erin, index=1, answer=2))
    assert st == 200, body
    assert answers(full, "erin")[0] == [1, 2]
    print("ok: a full disk while serving: 500 with the cause, the file untouched, the answer "
          "accepted once there is room:", refused)

    # Readers while answers are written (the server's thread pool; under ThreadSanitizer in
    # scripts/test.sh): every state a reader sees is whole and progress never goes backwards.
    seen, broken = [], []

    def reader():
        last = -1
        for _ in range(40):
            st, body = http("GET", f"{base_e}/api/state?p=erin&t={token_e}")
            s = json.loads(body) if st == 200 else None
            done = s["similarity"]["done"] + s["preference"]["done"] if s else -2
            if done < last:
                broken.append((st, body))
            last = done
            seen.append(done)
    readers = [threading.Thread(target=reader) for _ in range(4)]
    for r in readers:
        r.start()
    for kind, index, answer in (("similarity", 2, 0), ("preference", 0, 1), ("preference", 1, 0.5)):
        st, body = http("POST", f"{base_e}/api/answer", dict(erin, kind=kind, index=index,
                                                              answer=answer))
        assert st == 200, body
    for r in readers:
        r.join()
    srv_e.terminate()
    srv_e.wait()
    assert not broken and min(seen) >= 2 and max(seen) <= 5, (broken[:2], set(seen))
    sim, pref, _, _ = answers(full, "erin")
    assert sim == [1, 2, 0] and pref == [1.0, 0.5], (sim, pref)
    # SIGTERM stops the server with a line saying what was saved, and its lock goes with it.
    err = srv_e.stderr.read()
    assert srv_e.returncode == 0 and "stopped (SIGTERM); erin answered 3 of 3 similarity and 2 " \
        "of 2 preference queries" in err, (srv_e.returncode, err)
    assert not os.path.exists(full + ".lock"), os.listdir(os.path.dirname(full))
    print(f"ok: {len(seen)} state reads by 4 threads while 3 answers were written: each whole, "
          f"progress monotone ({sorted(set(seen))})")

    if os.environ.get("STUDY_BROWSER") == "1":
        web = os.path.join(SRC, "app", "study_web")
        p = subprocess.run(["node", os.path.join(SRC, "tests", "study_browser.mjs"), url],
                           cwd=web, capture_output=True, text=True, timeout=300)
        if p.returncode != 0:
            sys.exit(f"FAIL: browser test\n{p.stdout}\n{p.stderr}")
        print(p.stdout.strip())
        sim, pref, ms, _ = answers(study, "alice")
        assert sim[:2] == [2, 0] and len(sim) == 3 and len(pref) == 2, (sim, pref)
        assert all(m > 0 for m in ms[2:]), ms
        print("ok: chromium answered the rest through the page; the file holds every answer")
        # The JacoRobot page (three.js 3-D views, replay buttons) and Driver's (each trajectory a
        # path of road points) run in chromium to the end as well.
        browse_to_the_end(tmp, web, "jaco2", "carol", "Stay high above the table.", "arm")
        print("ok: the JacoRobot page (3-D arm views, shared camera, keys) ran to the end in chromium")
        browse_to_the_end(tmp, web, "driver", "dora", "Keep to your lane.", "path")
        print("ok: the Driver page (road paths drawn to fit) ran to the end in chromium")
    srv.kill()
print("PASS")
