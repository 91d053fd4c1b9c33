#!/usr/bin/env python3
"""A loopback HTTP server for the fetch tests that serves files from a directory and
injects faults by path. Prints its port on the first line of stdout, then serves until
killed. Paths (NAME is a file in the directory):

  /ok/NAME                 the file, with Content-Length
  /chunked/NAME            the file, chunked (no Content-Length)
  /flaky/K/NAME            HTTP 503 for the first K requests of this path, then the file
  /reset/K/NAME            the first K requests: headers, a few bytes, then the connection
                           is reset; then the file
  /truncate/NAME           Content-Length of the whole file, half the bytes, then close
  /slow/NAME               one byte per half second (a low-speed abort must stop it)
  /redirect/N/NAME         N redirects (302) in a row, then /ok/NAME
  /loop                    redirects to itself forever
  /to/URL-ENCODED-TARGET   a 302 to any target (link-local, file://, https→http ...)
  /status/CODE             an empty response with that status
  /huge                    declares a Content-Length of 1 TB, sends a little
  /endless                 chunked body that never ends (size cap must stop it)
  /range/NAME              the file, honouring "Range: bytes=a-b" (206 + Content-Range)
  /range-then-503/K/NAME   as /range/NAME for the first K requests of this path, then 503
  /counts                  JSON: requests seen per path
  /bytes                   JSON: body bytes sent per path
"""
import json
import os
import socket
import struct
import sys
import threading
import time
import urllib.parse
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

ROOT = sys.argv[1] if len(sys.argv) > 1 else "."
COUNTS = {}
BYTES = {}
LOCK = threading.RLock()


def bump(path):
    with LOCK:
        COUNTS[path] = COUNTS.get(path, 0) + 1
        return COUNTS[path]


class Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"

    def log_message(self, *args):
        pass

    def body_of(self, name):
        path = os.path.join(ROOT, os.path.basename(name))
        with open(path, "rb") as f:
            return f.read()

    def send_bytes(self, data, status=200, length=None):
        with LOCK:
            BYTES[self.path] = BYTES.get(self.path, 0) + len(data)
        self.send_response(status)
        self.send_header("Content-Length", str(len(data) if length is None else length))
        self.end_headers()
        self.wfile.write(data)

    def reset(self):
        # SO_LINGER with a zero timeout: close() sends a TCP RST.
        self.connection.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        self.connection.close()
        self.close_connection = True

    def do_GET(self):
        n = bump(self.path)
        parts = self.path.lstrip("/").split("/")
        kind = parts[0]
        try:
            if kind == "ok":
                self.send_bytes(self.body_of(parts[1]))
            elif kind == "chunked":
                data = self.body_of(parts[1])
                self.send_response(200)
                self.send_header("Transfer-Encoding", "chunked")
                self.end_headers()
                for i in range(0, len(data), 4096):
                    piece = data[i:i + 4096]
                    self.wfile.write(b"%x\r\n%s\r\n" % (len(piece), piece))
                self.wfile.write(b"0\r\n\r\n")
            elif kind == "flaky":
                if n <= int(parts[1]):
                    self.send_bytes(b"busy", status=503)
                else:
                    self.send_bytes(self.body_of(parts[2]))
            elif kind == "reset":
                if n <= int(parts[1]):
                    data = self.body_of(parts[2])
                    self.send_response(200)
                    self.send_header("Content-Length", str(len(data)))
                    self.end_headers()
                    self.wfile.write(data[:10])
                    self.wfile.flush()
                    self.reset()
                else:
                    self.send_bytes(self.body_of(parts[2]))
            elif kind == "truncate":
                data = self.body_of(parts[1])
                self.send_response(200)
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data[: len(data) // 2])
                self.wfile.flush()
                self.close_connection = True
            elif kind == "slow":
                data = self.body_of(parts[1])
                self.send_response(200)
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                for b in data:
                    self.wfile.write(bytes([b]))
                    self.wfile.flush()
                    time.sleep(0.5)
            elif kind == "redirect":
                left = int(parts[1])
                target = "/ok/" + parts[2] if left <= 0 else "/redirect/%d/%s" % (left - 1, parts[2])
                self.send_response(302)
                self.send_header("Location", target)
                self.send_header("Content-Length", "0")
                self.end_headers()
            elif kind == "loop":
                self.send_response(302)
                self.send_header("Location", "/loop")
                self.send_header("Content-Length", "0")
                self.end_headers()
            elif kind == "to":
                self.send_response(302)
                self.send_header("Location", urllib.parse.unquote("/".join(parts[1:])))
                self.send_header("Content-Length", "0")
                self.end_headers()
            elif kind == "status":
                self.send_bytes(b"", status=int(parts[1]))
            elif kind == "huge":
                self.send_bytes(b"x" * 100, length=10 ** 12)
                self.close_connection = True
            elif kind == "endless":
                self.send_response(200)
                self.send_header("Transfer-Encoding", "chunked")
                self.end_headers()
                piece = b"y" * 65536
                while True:
                    self.wfile.write(b"%x\r\n%s\r\n" % (len(piece), piece))
            elif kind in ("range", "range-then-503"):
                if kind == "range-then-503":
                    if n > int(parts[1]):
                        self.send_bytes(b"busy", status=503)
                        return
                    parts = ["range", parts[2]]
                data = self.body_of(parts[1])
                spec = self.headers.get("Range", "")
                if not spec.startswith("bytes="):
                    self.send_bytes(data)
                    return
                first, _, last = spec[len("bytes="):].partition("-")
                first = int(first)
                last = min(int(last) if last else len(data) - 1, len(data) - 1)
                if first >= len(data):
                    self.send_response(416)
                    self.send_header("Content-Range", "bytes */%d" % len(data))
                    self.send_header("Content-Length", "0")
                    self.end_headers()
                    return
                piece = data[first:last + 1]
                with LOCK:
                    BYTES[self.path] = BYTES.get(self.path, 0) + len(piece)
                self.send_response(206)
                self.send_header("Content-Range", "bytes %d-%d/%d" % (first, last, len(data)))
                self.send_header("Content-Length", str(len(piece)))
                self.end_headers()
                self.wfile.write(piece)
            elif kind == "counts":
                with LOCK:
                    self.send_bytes(json.dumps(COUNTS).encode())
            elif kind == "bytes":
                with LOCK:
                    self.send_bytes(json.dumps(BYTES).encode())
            else:
                self.send_bytes(b"not found", status=404)
        except FileNotFoundError:
            self.send_bytes(b"not found", status=404)
        except (BrokenPipeError, ConnectionResetError, OSError):
            self.close_connection = True


class Server(ThreadingHTTPServer):
    daemon_threads = True

    def handle_error(self, request, client_address):
        pass  # clients that hang up on purpose (size caps, low-speed aborts) are expected


def main():
    server = Server(("127.0.0.1", 0), Handler)
    print(server.server_address[1], flush=True)
    server.serve_forever()


if __name__ == "__main__":
    main()
