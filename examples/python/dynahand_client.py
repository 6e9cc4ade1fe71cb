#!/usr/bin/env python3
"""Reads the pose stream of `dynahand serve` and prints the index fingertip position.

Standard library only: the WebSocket opening handshake and framing (RFC 6455) are done by
hand below, so this file can be copied anywhere. The messages are described in
docs/formats/viewer-stream.md.

    dynahand serve synth:wave &     # prints: ... stream at ws://127.0.0.1:8080/?token=...
    python3 examples/python/dynahand_client.py --url 'ws://127.0.0.1:8080/?token=...' --frames 30
    python3 examples/python/dynahand_client.py --port 8080 --token ... --frames 30

The server lets in only its own page and clients that present the token it printed at start
(docs/commands.md, "dynahand serve"); without it the handshake is refused with 403.
"""

import argparse
import base64
import hashlib
import json
import os
import socket
import struct
import sys
import urllib.parse

WEBSOCKET_GUID = "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"  # fixed by RFC 6455
INDEX_TIP = 8  # keypoints21 index of the index fingertip (MediaPipe order)
MAX_MESSAGE_BYTES = 64 << 20  # refuse anything larger than a sane frame


class WebSocket:
    """A minimal client: text messages in, masked text frames out, ping answered."""

    def __init__(self, host, port, path="/", timeout=10.0, sock=None, token=None, origin=None):
        """token: the server's per-run token, added to the path as ?token=...; origin: an
        Origin header to send (browsers do; this client normally does not). sock: an
        unconnected socket to use (e.g. with options set); default a new one."""
        if token:
            path += ("&" if "?" in path else "?") + "token=" + urllib.parse.quote(token, safe="")
        if sock is None:
            self.sock = socket.create_connection((host, port), timeout=timeout)
        else:
            self.sock = sock
            self.sock.settimeout(timeout)
            self.sock.connect((host, port))
        key = base64.b64encode(os.urandom(16)).decode()
        request = (
            f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
        )
        if origin:
            request += f"Origin: {origin}\r\n"
        self.sock.sendall((request + "\r\n").encode())
        self.buffer = b""
        header = self._read_until(b"\r\n\r\n").decode("latin-1")
        status = header.split("\r\n", 1)[0]
        if " 101 " not in status + " ":
            self.sock.close()
            reason = self.buffer.decode("latin-1").strip().split("\n")[0][:300]
            raise ConnectionError(f"handshake refused: {status}: {reason}" if reason
                                  else f"handshake refused: {status}")
        expected = base64.b64encode(hashlib.sha1((key + WEBSOCKET_GUID).encode()).digest()).decode()
        accept = [
            line.split(":", 1)[1].strip()
            for line in header.split("\r\n")[1:]
            if line.lower().startswith("sec-websocket-accept:")
        ]
        if accept != [expected]:
            raise ConnectionError("handshake: wrong Sec-WebSocket-Accept")

    def _read_exact(self, n):
        while len(self.buffer) < n:
            chunk = self.sock.recv(65536)
            if not chunk:
                raise ConnectionError("connection closed by the server")
            self.buffer += chunk
        data, self.buffer = self.buffer[:n], self.buffer[n:]
        return data

    def _read_until(self, marker):
        while marker not in self.buffer:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise ConnectionError("connection closed during the handshake")
            self.buffer += chunk
        head, self.buffer = self.buffer.split(marker, 1)
        return head

    def _send_frame(self, opcode, payload):
        mask = os.urandom(4)  # clients must mask every frame
        n = len(payload)
        if n < 126:
            header = struct.pack("!BB", 0x80 | opcode, 0x80 | n)
        elif n < 65536:
            header = struct.pack("!BBH", 0x80 | opcode, 0x80 | 126, n)
        else:
            header = struct.pack("!BBQ", 0x80 | opcode, 0x80 | 127, n)
        masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
        self.sock.sendall(header + mask + masked)

    def send_text(self, text):
        self._send_frame(0x1, text.encode())

    def receive_text(self):
        """The next text message; None when the server closed the connection."""
        parts = []
        while True:
            b0, b1 = self._read_exact(2)
            fin, opcode, n = b0 & 0x80, b0 & 0x0F, b1 & 0x7F
            if n == 126:
                (n,) = struct.unpack("!H", self._read_exact(2))
            elif n == 127:
                (n,) = struct.unpack("!Q", self._read_exact(8))
            if n > MAX_MESSAGE_BYTES:
                raise ConnectionError(f"message of {n} bytes is too large")
            mask = self._read_exact(4) if b1 & 0x80 else None
            payload = self._read_exact(n)
            if mask:
                payload = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
            if opcode == 0x8:  # close: answer it and stop
                self._send_frame(0x8, payload[:2])
                return None
            if opcode == 0x9:  # ping
                self._send_frame(0xA, payload)
                continue
            if opcode == 0xA:  # pong
                continue
            parts.append(payload)  # text (0x1), binary (0x2) or a continuation (0x0)
            if fin:
                return b"".join(parts).decode("utf-8")

    def close(self):
        try:
            self._send_frame(0x8, struct.pack("!H", 1000))
        finally:
            self.sock.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--url", help="the stream address dynahand printed, "
                        "ws://HOST:PORT/?token=... (instead of --host, --port and --token)")
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=8080)
    parser.add_argument("--token", help="the token dynahand printed (its ?token=...)")
    parser.add_argument("--frames", type=int, default=0, help="stop after this many frames")
    args = parser.parse_args()

    host, port, path = args.host, args.port, "/"
    if args.url:
        url = urllib.parse.urlsplit(args.url)
        if url.scheme not in ("ws", "http") or not url.hostname:
            parser.error(f"--url: expected ws://HOST:PORT/?token=..., got {args.url}")
        host, port = url.hostname, url.port or 80
        path = (url.path or "/") + (f"?{url.query}" if url.query else "")
    try:
        ws = WebSocket(host, port, path=path, token=args.token)
    except (ConnectionError, OSError) as error:
        print(f"dynahand_client: {host}:{port}: {error}", file=sys.stderr)
        return 1
    frames = 0
    try:
        while args.frames == 0 or frames < args.frames:
            text = ws.receive_text()
            if text is None:
                break
            message = json.loads(text)
            if message.get("type") == "hello":
                print(f"connected to {message['source']} (stream version {message['version']})")
                continue
            if message.get("type") != "frame":
                continue
            frames += 1
            hand = message["track"]["hands"][0]
            if hand["tracked"]:
                x, y, z = (1000.0 * v for v in hand["keypoints21"][INDEX_TIP])
                print(f"frame {message['index']}: index fingertip "
                      f"x {x:7.1f} y {y:7.1f} z {z:7.1f} mm", flush=True)
            else:
                print(f"frame {message['index']}: no hand", flush=True)
    finally:
        ws.close()
    return 0 if frames > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
