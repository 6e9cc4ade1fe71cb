#!/usr/bin/env python3
"""Tests `dynahand serve`'s WebSocket stream from outside, with the Python example client.

    viewer_stream_test.py DYNAHAND EXAMPLES_PYTHON_DIR

Starts `dynahand serve synth:wave --port 0`, then checks: the printed addresses carry a
128-bit token; only the page's own origin or the token opens the WebSocket (another origin,
or no Origin and no token, is answered 403 and logged); the example client prints the index
fingertip given the token (--url or --token) and fails with the 403 without it; malformed
and oversized client messages close only that client while another keeps receiving; a
client that never reads gets frames dropped (gaps in its frame indices) without slowing the
others; the HTTP side refuses paths outside the page folder.
"""

import json
import re
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request

DYNAHAND, EXAMPLES = sys.argv[1], sys.argv[2]
sys.path.insert(0, EXAMPLES)
from dynahand_client import WebSocket  # noqa: E402  (the example under test)

results = {"passed": 0, "failed": 0}


def check(name, condition, detail=""):
    results["passed" if condition else "failed"] += 1
    print(f"{'ok  ' if condition else 'FAIL'} {name}{(': ' + detail) if detail else ''}", flush=True)


def frames(ws, count, timeout=30.0):
    """The next `count` frame messages (hello and others skipped)."""
    out, deadline = [], time.time() + timeout
    while len(out) < count and time.time() < deadline:
        text = ws.receive_text()
        if text is None:
            break
        message = json.loads(text)
        if message["type"] == "frame":
            out.append(message)
    return out


def closed_after(ws, timeout=10.0):
    """True when the server closes `ws` (an error message may come first)."""
    ws.sock.settimeout(timeout)
    try:
        while True:
            text = ws.receive_text()
            if text is None:
                return True
    except (ConnectionError, OSError):
        return True
    except socket.timeout:
        return False


def handshake(port, **options):
    """'101' when the server accepts a WebSocket opened with `options`, else its refusal."""
    try:
        WebSocket("127.0.0.1", port, **options).close()
        return "101"
    except ConnectionError as error:
        return str(error)


server = subprocess.Popen([DYNAHAND, "serve", "synth:wave", "--port", "0", "--init", "gt",
                           "--max-client-queue", "100000"],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
server_log = ""
try:
    banner = server.stdout.readline()
    match = re.search(r"(ws://127\.0\.0\.1:(\d+)/\?token=([0-9a-f]+))\s", banner)
    if not match:
        raise SystemExit(f"no stream address with a token in the server's first line: {banner!r}")
    stream_url, port, token = match.group(1), int(match.group(2)), match.group(3)
    check("the printed token is 128 bits in hex", len(token) == 32, token)
    check("the page's printed address carries the same token",
          re.search(rf"http://127\.0\.0\.1:{port}/\?token={token}\s", banner) is not None
          or "viewer page unavailable" in banner, banner.strip())

    # Who may open the WebSocket: the page's own origin, or whoever has the token.
    answer = handshake(port, origin="http://evil.example.com")
    check("another origin is refused with 403", "403" in answer and "101" not in answer, answer)
    check("the page's own origin is accepted (127.0.0.1)",
          handshake(port, origin=f"http://127.0.0.1:{port}") == "101")
    check("the page's own origin is accepted (localhost)",
          handshake(port, origin=f"http://localhost:{port}") == "101")
    answer = handshake(port)
    check("no Origin and no token is refused with 403", "403" in answer, answer)
    check("a wrong token is refused with 403", "403" in handshake(port, token="0" * 32))
    check("no Origin with the token is accepted", handshake(port, token=token) == "101")

    # The example client, as a user runs it: with the printed address, or --token.
    client = [sys.executable, f"{EXAMPLES}/dynahand_client.py"]
    run = subprocess.run(client + ["--url", stream_url, "--frames", "15"],
                         capture_output=True, text=True, timeout=120)
    tips = re.findall(r"index fingertip x +(-?[\d.]+) y +(-?[\d.]+) z +(-?[\d.]+) mm", run.stdout)
    check("example client exits 0", run.returncode == 0, run.stderr.strip()[-200:])
    check("example client prints the index fingertip", len(tips) >= 10, f"{len(tips)} of 15 frames")
    check("fingertip depth is in front of the camera (200-800 mm)",
          bool(tips) and all(200.0 < float(z) < 800.0 for _, _, z in tips))
    run = subprocess.run(client + ["--port", str(port), "--token", token, "--frames", "2"],
                         capture_output=True, text=True, timeout=120)
    check("example client with --token reads frames", run.returncode == 0 and
          run.stdout.count("frame ") == 2, (run.stdout + run.stderr).strip()[-200:])
    run = subprocess.run(client + ["--port", str(port), "--frames", "2"],
                         capture_output=True, text=True, timeout=120)
    check("example client without the token fails with the 403",
          run.returncode != 0 and "403" in run.stderr, run.stderr.strip()[-200:])

    watcher = WebSocket("127.0.0.1", port, token=token)
    first = frames(watcher, 3)
    check("a frame carries track, cloud and truth",
          bool(first) and {"track", "cloud", "samples", "truth"} <= set(first[0]))

    bad = WebSocket("127.0.0.1", port, token=token)
    bad.send_text("this is not JSON")
    check("a malformed message closes that client", closed_after(bad))
    check("others keep receiving after a malformed message", len(frames(watcher, 5)) == 5)

    unknown = WebSocket("127.0.0.1", port, token=token)
    unknown.send_text('{"type":"control","action":"explode"}')
    reply = None
    unknown.sock.settimeout(10)
    while reply is None:
        message = json.loads(unknown.receive_text())
        if message["type"] == "error":
            reply = message
    check("an unknown action is answered with an error", "unknown action" in reply["message"])
    check("and that client stays connected", len(frames(unknown, 2)) == 2)
    unknown.close()

    big = WebSocket("127.0.0.1", port, token=token)
    big.send_text(json.dumps({"type": "control", "action": "pause", "padding": "x" * 20000}))
    check("an oversized message closes that client", closed_after(big))
    check("others keep receiving after an oversized message", len(frames(watcher, 5)) == 5)

    # A client that stops reading: its socket buffers fill, the server skips frames for it.
    # (A small receive window and, on the server, --max-client-queue keep this quick.)
    small = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    small.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    slow = WebSocket("127.0.0.1", port, sock=small, token=token)
    started = time.time()
    during = frames(watcher, 150, timeout=120)
    elapsed = time.time() - started
    rate = len(during) / elapsed
    check("a client that does not read does not slow the others",
          len(during) == 150 and rate > 1.0, f"{rate:.1f} frames/s while it stalls")
    # What was already on its way (socket buffers, the write in flight) arrives in order,
    # then the frames the server skipped show as a gap.
    slow.sock.settimeout(10)
    indices = [m["index"] for m in frames(slow, 150)]
    gaps = sum(1 for a, b in zip(indices, indices[1:]) if b != a + 1 and b != 0)
    check("the stalled client skipped frames instead of queueing them all", gaps >= 1,
          f"indices {indices[:3]}..{indices[-3:]}, {gaps} gaps")
    slow.close()
    watcher.close()

    def status(path):
        try:
            return urllib.request.urlopen(f"http://127.0.0.1:{port}{path}", timeout=10).status
        except urllib.error.HTTPError as error:
            return error.code

    root = status("/")
    check("GET / answers (200 with the page, 503 without)", root in (200, 503))
    if root == 200:
        check("paths outside the page folder are refused",
              status("/%2e%2e/CMakeCache.txt") == 404 and status("/a/../../etc/passwd") == 404)
finally:
    server.send_signal(2)  # SIGINT: the command's Ctrl-C
    try:
        server_log = server.communicate(timeout=20)[1]
    except subprocess.TimeoutExpired:
        server.kill()

# Each refused handshake above (three, and the example client's) left one line on stderr.
refusals = [line for line in server_log.splitlines() if "refused a WebSocket connection" in line]
check("each refused handshake is logged in one line", len(refusals) == 4,
      f"{len(refusals)} lines: {refusals[:2]}")
check("the log names the refused origin",
      any("origin http://evil.example.com" in line for line in refusals))

print(f"{results['passed']} passed, {results['failed']} failed")
sys.exit(1 if results["failed"] else 0)
