"""A WebSocket and HTTP client of teejet-web for the tests, standard library only: it stands in
for the page (tests/web/server_e2e.py, tests/security/roles_test.py)."""

import base64
import json
import os
import socket
import struct
import sys
import time
import urllib.error
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from waiting import eventually  # noqa: E402 (tests/support)


class Failure(Exception):
    pass


class Closed(Failure):
    """The server closed the WebSocket with a close frame: `code` is its status code."""

    def __init__(self, code):
        super().__init__(f"the server closed the WebSocket with {code}")
        self.code = code


TEXT, CONTINUATION, CLOSE, PING, PONG = 0x1, 0x0, 0x8, 0x9, 0xA


def upgrade_request(port, origin=None):
    key = base64.b64encode(os.urandom(16)).decode()
    request = (f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
               f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
               "Sec-WebSocket-Version: 13\r\n")
    if origin:
        request += f"Origin: {origin}\r\n"
    return (request + "\r\n").encode()


class WebSocket:
    def __init__(self, port, origin=None, receive_buffer=None, sock=None):
        if sock is None:
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            sock.settimeout(10)
            if receive_buffer:
                # Before connecting: the window the server may fill stays this small.
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, receive_buffer)
            sock.connect(("127.0.0.1", port))
            sock.sendall(upgrade_request(port, origin))
        self.sock = sock
        head = b""
        try:
            while b"\r\n\r\n" not in head:
                chunk = self.sock.recv(1)
                if not chunk:
                    break
                head += chunk
        except OSError:
            pass
        self.status = head.split(b"\r\n")[0].decode()

    @classmethod
    def after_request(cls, sock):
        """The WebSocket whose upgrade request was already sent on `sock`."""
        return cls(None, sock=sock)

    def __repr__(self):
        return f"<WebSocket {self.status!r}>"

    def _exact(self, n):
        data = b""
        while len(data) < n:
            try:
                chunk = self.sock.recv(n - len(data))
            except socket.timeout:
                raise Failure("no message from teejet-web within 10 s") from None
            if not chunk:
                raise Failure("the server closed the WebSocket")
            data += chunk
        return data

    def receive_frame(self):
        """One frame as it came: (opcode, payload). Server frames are never masked."""
        head = self._exact(2)
        length = head[1] & 0x7F
        if length == 126:
            length = struct.unpack(">H", self._exact(2))[0]
        elif length == 127:
            length = struct.unpack(">Q", self._exact(8))[0]
        return head[0] & 0x0F, self._exact(length)

    def receive(self):
        """The next text message as JSON, answering pings (a browser does) on the way; Closed
        when the server closes."""
        while True:
            opcode, payload = self.receive_frame()
            if opcode == PING:
                self.sock.sendall(self.frame(payload, opcode=PONG))
            elif opcode == CLOSE:
                raise Closed(struct.unpack(">H", payload[:2])[0] if len(payload) >= 2 else None)
            elif opcode == TEXT:
                return json.loads(payload.decode())

    def close_code(self, deadline_s=20):
        """Reads until the server closes: its close code, or None when the connection ended
        without a close frame or the server did not close within `deadline_s`."""
        end = time.monotonic() + deadline_s
        try:
            while time.monotonic() < end:
                self.receive()
            return None
        except Closed as closed:
            return closed.code
        except (Failure, OSError):
            return None

    @staticmethod
    def frame(data, opcode=TEXT, fin=True, rsv=0, masked=True, length=None):
        """A client frame; `length` claims another payload length than the data's."""
        if isinstance(data, str):
            data = data.encode()
        n = len(data) if length is None else length
        first = (0x80 if fin else 0) | (rsv << 4) | opcode
        mask_bit = 0x80 if masked else 0
        if n < 126:
            head = bytes([first, mask_bit | n])
        elif n < 65536:
            head = bytes([first, mask_bit | 126]) + struct.pack(">H", n)
        else:
            head = bytes([first, mask_bit | 127]) + struct.pack(">Q", n)
        if not masked:
            return head + data
        mask = os.urandom(4)
        return head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(data))

    def send(self, text):
        self.sock.sendall(self.frame(text))

    def answer(self, text, deadline_s=20):
        """Sends `text` and returns the answer, skipping the updates in between (they keep
        coming, so each receive() is quick: only the deadline ends the wait). A status of what
        the answer says was sent must not come before it: the page matches statuses to the ids
        the answer gives it (AssertionError otherwise)."""
        self.send(text)
        skipped = []

        def next_message():
            message = self.receive()
            skipped.append(message)
            return message

        reply = eventually(next_message, deadline_s, f"an answer to {text[:60]}",
                           ok=lambda message: message["type"] in ("sent", "refused"), interval=0)
        commands = {c["command_id"] for c in reply.get("commands", []) if "command_id" in c}
        changes = {c["change_id"] for c in reply.get("changes", []) if "change_id" in c}
        early = [status for message in skipped[:-1] for status in message.get("statuses", [])
                 if status.get("command_id") in commands or status.get("change_id") in changes]
        if early:
            raise AssertionError(f"statuses before the answer {reply} that gives their ids: {early}")
        return reply


def raw_http(port, path, host, extra=""):
    """One request as written, read to its end: (status line, {header: value}, body). For the
    headers urllib would not send (a foreign Host) and the handshakes it cannot make."""
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        close = "" if "Connection:" in extra else "Connection: close\r\n"
        sock.sendall(f"GET {path} HTTP/1.1\r\nHost: {host}\r\n{close}{extra}\r\n".encode())
        data = b""
        while b"\r\n\r\n" not in data or not data.startswith(b"HTTP/1.1 101"):
            try:
                chunk = sock.recv(65536)
            except socket.timeout:
                break
            if not chunk:
                break
            data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    lines = head.decode(errors="replace").split("\r\n")
    headers = dict(line.split(": ", 1) for line in lines[1:] if ": " in line)
    return lines[0], headers, body.decode(errors="replace")


def http_get(port, path, method="GET", deadline_s=5):
    request = urllib.request.Request(f"http://127.0.0.1:{port}{path}", method=method)
    try:
        with urllib.request.urlopen(request, timeout=deadline_s) as response:
            return response.status, response.read().decode()
    except urllib.error.HTTPError as error:
        return error.code, ""


def valves(port):
    """GET /api/valves: the listing, empty while the server does not answer yet."""
    try:
        status, body = http_get(port, "/api/valves")
    except OSError:  # not listening yet
        return []
    return json.loads(body) if status == 200 else []
