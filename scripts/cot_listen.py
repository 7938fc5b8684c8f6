#!/usr/bin/python3
"""Listens for Cursor-on-Target events on a loopback UDP port and summarizes them.

A stand-in for a TAK client when running the TAK bridge locally (scripts/run_main.sh):

  scripts/cot_listen.py --port 16969 [--seconds 60]      (stops at SIGINT/SIGTERM otherwise)

Every datagram is parsed as XML; at the end it prints the events per type, datagrams that were
not CoT XML, and the latest event of the UAV, of each zone and of each track (uid, point, remarks).
Binds 127.0.0.1 only.
"""
import argparse
import signal
import socket
import sys
import time
import xml.etree.ElementTree as ET


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--seconds", type=float, default=0.0, help="0: until SIGINT/SIGTERM")
    args = ap.parse_args()
    if not 1 <= args.port <= 65535:
        sys.exit("cot_listen.py: --port %d: expected 1..65535" % args.port)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", args.port))
    sock.settimeout(0.2)
    stop = []
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    end = time.time() + args.seconds if args.seconds > 0 else float("inf")
    counts, bad, latest = {}, 0, {}
    while not stop and time.time() < end:
        try:
            data = sock.recv(65536)
        except socket.timeout:
            continue
        except InterruptedError:
            continue
        try:
            ev = ET.fromstring(data.decode("utf-8"))
            if ev.tag != "event":
                raise ValueError("root is <%s>" % ev.tag)
        except (ValueError, ET.ParseError, UnicodeDecodeError):
            bad += 1
            continue
        counts[ev.get("type")] = counts.get(ev.get("type"), 0) + 1
        latest[ev.get("uid")] = ev
    total = sum(counts.values())
    print("cot_listen: %d CoT events on udp://127.0.0.1:%d, %d not CoT XML" % (total, args.port, bad))
    for t in sorted(counts):
        print("  %-12s %d" % (t, counts[t]))
    for uid in sorted(latest):
        ev = latest[uid]
        p = ev.find("point")
        remarks = ev.findtext("detail/remarks") or ""
        print("  %-28s %s lat %s lon %s hae %s ce %s: %s" % (
            uid, ev.get("type"), p.get("lat"), p.get("lon"), p.get("hae"), p.get("ce"), remarks))
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
