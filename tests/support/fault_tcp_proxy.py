#!/usr/bin/env python3
"""A loopback TCP proxy for the S3 publish tests that injects connection faults by
schedule. Prints its port on the first line of stdout, then serves until killed.

Usage: fault_tcp_proxy.py TARGET_PORT PLAN

PLAN is a comma-separated list of steps, each consuming accepted connections in turn:
  pass:N   forward the next N connections to 127.0.0.1:TARGET_PORT unchanged
  reset:N  reset the next N connections at once (TCP RST, nothing forwarded)
N may be '*' (every further connection). After the last step connections pass.
Example: 'pass:4,reset:*' lets four requests through, then fails every one after them.
The requests are forwarded byte for byte, so SigV4 signatures made for the proxy's
host:port stay valid (the target sees the same Host header).
"""
import socket
import struct
import sys
import threading

TARGET = int(sys.argv[1])
PLAN = []
for step in sys.argv[2].split(","):
    kind, count = step.split(":")
    PLAN.append([kind, None if count == "*" else int(count)])
LOCK = threading.Lock()


def next_action():
    with LOCK:
        while PLAN:
            kind, left = PLAN[0]
            if left is None:
                return kind
            if left > 0:
                PLAN[0][1] = left - 1
                return kind
            PLAN.pop(0)
        return "pass"


def pump(source, sink):
    try:
        while True:
            data = source.recv(65536)
            if not data:
                break
            sink.sendall(data)
    except OSError:
        pass
    finally:
        for s in (sink, source):
            try:
                s.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass


def serve(client):
    if next_action() == "reset":
        client.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        client.close()
        return
    try:
        upstream = socket.create_connection(("127.0.0.1", TARGET))
    except OSError:
        client.close()
        return
    back = threading.Thread(target=pump, args=(upstream, client), daemon=True)
    back.start()
    pump(client, upstream)
    back.join()
    client.close()
    upstream.close()


def main():
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", 0))
    listener.listen(64)
    print(listener.getsockname()[1], flush=True)
    while True:
        client, _ = listener.accept()
        threading.Thread(target=serve, args=(client,), daemon=True).start()


if __name__ == "__main__":
    main()
