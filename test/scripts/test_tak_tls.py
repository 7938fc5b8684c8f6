#!/usr/bin/python3
"""The TAK link over mutual TLS on loopback, judged from outside.

A test CA with server and client certificates is made by openssl (test/scripts/tak_pki.sh); a
TLS listener written here with Python's ssl module requires the client certificate, and plays
TAK Server's side of the TAK Protocol negotiation. $HAMERITT_BIN_DIR/hameritt_tak_check (the
bridge's sender) sends events to it:
  * PEM certificate + encrypted key, PEM trust store, CoT XML: every event arrives and parses
    (ElementTree);
  * PKCS#12 client + PKCS#12 trust store + CA pin, TAK Protocol Version 1 after the negotiation:
    every event arrives in 0xbf-framed messages that the npm package @tak-ps/node-cot
    (CoTParser.from_proto) decodes to the uid, type, point, callsign, track and remarks sent;
  * UDP mesh in Version 1 (0xbf 0x01 0xbf): the same judge;
  * refused, each reason printed once while the sender keeps retrying, nothing sent: an
    untrusted server certificate, an expired one, no client certificate and an unknown client certificate (the
    server refuses), a name mismatch, a wrong pin, a wrong PKCS#12 password, a server that closes
    the handshake; a plaintext listener never sees CoT (no fallback to plaintext).
Negative controls: the arrival check reports a missing event, node-cot rejects a damaged payload.
node-cot is installed with npm into the build tree (a cache kept between runs); without the
registry the test exits 77 (skipped), and fails under CI=true.
Prints one line per failure and a "N passed, N failed" summary; exits 1 on any failure.
"""

import base64
import json
import os
import re
import shutil
import socket
import ssl
import struct
import subprocess
import sys
import tempfile
import threading
import time
import xml.etree.ElementTree as ET

NODE_COT = "@tak-ps/node-cot@14.23.2"
EVENTS = 5

passed = 0
failed = 0


def check(name, cond, why=""):
    global passed, failed
    if cond:
        passed += 1
    else:
        failed += 1
        print("FAIL %s: %s" % (name, why))
    return cond


def read_varint(buf, pos):
    value, shift = 0, 0
    while True:
        if pos >= len(buf):
            return None, pos
        b = buf[pos]
        pos += 1
        value |= (b & 0x7F) << shift
        if not b & 0x80:
            return value, pos
        shift += 7


class Listener:
    """A TLS (or plain) TCP listener on 127.0.0.1 that stores what each connection sends."""

    def __init__(self, pki, cert="server", tls=True, negotiate=False, close_at_once=False):
        self.events, self.frames, self.errors, self.raw = [], [], [], []
        self.negotiated = False
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.port = self.sock.getsockname()[1]
        self.ctx = None
        if tls:
            self.ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
            self.ctx.load_cert_chain(os.path.join(pki, cert + ".pem"), os.path.join(pki, cert + ".key"))
            self.ctx.load_verify_locations(os.path.join(pki, "ca.pem"))
            self.ctx.verify_mode = ssl.CERT_REQUIRED
        self.negotiate = negotiate
        self.close_at_once = close_at_once
        self.lock = threading.Lock()
        self.stop = False
        self.accepted = self.finished = 0  # connections accepted, and handled to their end
        threading.Thread(target=self.serve, daemon=True).start()

    def serve(self):
        self.sock.settimeout(0.1)
        while not self.stop:
            try:
                conn, _ = self.sock.accept()
            except socket.timeout:
                continue
            except OSError:
                return
            with self.lock:
                self.accepted += 1
            threading.Thread(target=self.handle_counted, args=(conn,), daemon=True).start()

    def handle_counted(self, conn):
        try:
            self.handle(conn)
        finally:
            with self.lock:
                self.finished += 1

    def settle(self, timeout=15.0):
        """Waits until every connection accepted so far has been read to its end (the client
        has exited: each ends at its close), so that what it sent is all stored; a fixed sleep
        lost the last event on a loaded machine. Returns whether they all ended in time."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            with self.lock:
                if self.finished == self.accepted:
                    return True
            time.sleep(0.02)
        return False

    def handle(self, conn):
        conn.settimeout(5)
        if self.close_at_once:  # reads what the client sent first, then hangs up
            try:
                self.raw.append(conn.recv(4096))
            except OSError:
                pass
            conn.close()
            return
        if self.ctx:
            try:
                conn = self.ctx.wrap_socket(conn, server_side=True)
            except (ssl.SSLError, OSError) as e:
                with self.lock:
                    self.errors.append(str(e))
                conn.close()
                return
        if self.negotiate:
            conn.sendall(b"<?xml version='1.0' encoding='UTF-8' standalone='yes'?>\n"
                         b"<event version='2.0' uid='protouid' type='t-x-takp-v' time='2026-01-01T00:00:00Z' "
                         b"start='2026-01-01T00:00:00Z' stale='2026-01-01T00:01:00Z' how='m-g'>"
                         b"<point lat='0.0' lon='0.0' hae='0.0' ce='999999' le='999999'/><detail>"
                         b"<TakControl><TakProtocolSupport version='1'/></TakControl></detail></event>")
        buf, proto = b"", False
        while True:
            try:
                data = conn.recv(65536)
            except (ssl.SSLError, OSError):
                break
            if not data:
                break
            buf += data
            while True:
                if proto:
                    if not buf:
                        break
                    if buf[0] != 0xBF:
                        with self.lock:
                            self.errors.append("stream byte %#x is not 0xbf" % buf[0])
                        return
                    n, pos = read_varint(buf, 1)
                    if n is None or len(buf) - pos < n:
                        break
                    with self.lock:
                        self.frames.append(buf[pos:pos + n])
                    buf = buf[pos + n:]
                    continue
                end = buf.find(b"</event>")
                if end < 0:
                    break
                event, buf = buf[:end + 8], buf[end + 8:]
                if b"t-x-takp-q" in event:
                    conn.sendall(b"<event version='2.0' uid='protouid' type='t-x-takp-r' "
                                 b"time='2026-01-01T00:00:00Z' start='2026-01-01T00:00:00Z' "
                                 b"stale='2026-01-01T00:01:00Z' how='m-g'><point lat='0.0' lon='0.0' "
                                 b"hae='0.0' ce='999999' le='999999'/><detail><TakControl>"
                                 b"<TakResponse status='true'/></TakControl></detail></event>")
                    proto = self.negotiated = True
                    continue
                with self.lock:
                    self.events.append(event)
        conn.close()

    def close(self):
        self.stop = True
        self.sock.close()


def run_check(binary, url, *args, seconds=30.0, env=None):
    """hameritt_tak_check's run and its summary line; it ends as soon as every event is sent."""
    cmd = [binary, url, "--events", str(EVENTS), "--seconds", str(seconds),
           "--reconnect-initial-s", "0.3", "--connect-timeout-s", "10"] + list(args)
    e = dict(os.environ)
    e.update(env or {})
    p = subprocess.run(cmd, capture_output=True, text=True, env=e, timeout=60)
    m = re.search(r"(\d+) of (\d+) events sent \(([^)]*)\), (\d+) connects of (\d+) attempts, "
                  r"(\d+) TLS failures, (\d+) send errors, (\d+) dropped", p.stdout)
    summary = None
    if m:
        summary = dict(sent=int(m[1]), events=int(m[2]), encoding=m[3], connects=int(m[4]),
                       attempts=int(m[5]), tls_failures=int(m[6]), send_errors=int(m[7]),
                       dropped=int(m[8]))
    return p, summary


def missing_events(uids):
    """The check of arrival: which of hameritt.check.0..EVENTS-1 are not in `uids` (or twice)."""
    want = ["hameritt.check.%d" % k for k in range(EVENTS)]
    return [u for u in want if uids.count(u) != 1] + sorted(set(uids) - set(want))


def check_xml_events(name, events):
    uids = []
    for raw in events:
        try:
            ev = ET.fromstring(raw.decode())
        except ET.ParseError as e:
            check(name + " parses", False, "%s: %r" % (e, raw[:80]))
            continue
        uids.append(ev.get("uid"))
        pt, contact = ev.find("point"), ev.find("detail/contact")
        check(name + " event content", ev.get("type") == "a-f-G-U-C" and pt is not None and
              abs(float(pt.get("lon")) + 71.1873) < 1e-6 and contact is not None and
              contact.get("callsign") == "HAMERITT-CHECK", raw[:200])
    check(name + ": every event arrives once", not missing_events(uids), missing_events(uids))


def install_node_cot(build_dir):
    """node-cot in <build>/node_cot (kept between runs); None when npm cannot reach the registry."""
    prefix = os.path.join(build_dir, "node_cot")
    marker = os.path.join(prefix, "node_modules", "@tak-ps", "node-cot", "package.json")
    if os.path.exists(marker):
        with open(marker) as f:
            if json.load(f).get("version") == NODE_COT.rsplit("@", 1)[1]:
                return prefix
    os.makedirs(prefix, exist_ok=True)
    if not os.path.exists(os.path.join(prefix, "package.json")):
        with open(os.path.join(prefix, "package.json"), "w") as f:
            json.dump({"name": "hameritt-node-cot-judge", "private": True}, f)
    try:
        p = subprocess.run(["npm", "install", "--prefix", prefix, "--no-audit", "--no-fund",
                            "--loglevel=error", NODE_COT], capture_output=True, text=True, timeout=240)
    except (OSError, subprocess.TimeoutExpired) as e:
        print("test_tak_tls: npm: %s" % e, file=sys.stderr)
        return None
    if p.returncode != 0:
        print("test_tak_tls: npm install %s failed:\n%s" % (NODE_COT, p.stderr[-2000:]), file=sys.stderr)
        return None
    return prefix


DECODE_MJS = r"""
import fs from 'node:fs';
import { CoTParser } from '@tak-ps/node-cot';
const items = JSON.parse(fs.readFileSync(0, 'utf8'));
const out = [];
for (const b64 of items) {
  try {
    const cot = await CoTParser.from_proto(Buffer.from(b64, 'base64'));
    const ev = cot.raw.event;
    const d = ev.detail || {};
    out.push({uid: ev._attributes.uid, type: ev._attributes.type, how: ev._attributes.how,
              time: ev._attributes.time, stale: ev._attributes.stale,
              lat: ev.point._attributes.lat, lon: ev.point._attributes.lon,
              hae: ev.point._attributes.hae, ce: ev.point._attributes.ce,
              callsign: d.contact ? d.contact._attributes.callsign : null,
              speed: d.track ? d.track._attributes.speed : null,
              course: d.track ? d.track._attributes.course : null,
              remarks: d.remarks ? d.remarks._text : null});
  } catch (e) {
    out.push({error: String(e && e.message || e)});
  }
}
process.stdout.write(JSON.stringify(out));
"""


def node_decode(prefix, payloads):
    script = os.path.join(prefix, "decode.mjs")
    with open(script, "w") as f:
        f.write(DECODE_MJS)
    p = subprocess.run(["node", script], input=json.dumps([base64.b64encode(x).decode() for x in payloads]),
                       capture_output=True, text=True, timeout=60, cwd=prefix)
    if p.returncode != 0:
        return [{"error": "node: " + p.stderr[-500:]}] * len(payloads)
    return json.loads(p.stdout)


def check_decoded(name, decoded):
    uids = []
    for k, d in enumerate(decoded):
        if not check(name + " decodes", "error" not in d, d.get("error")):
            continue
        uids.append(d["uid"])
        n = int(d["uid"].rsplit(".", 1)[1]) if d["uid"].startswith("hameritt.check.") else -1
        check(name + " content", d["type"] == "a-f-G-U-C" and d["how"] == "m-g" and
              abs(d["lat"] - (42.4851 + 1e-4 * n)) < 1e-9 and abs(d["lon"] + 71.1873) < 1e-9 and
              d["hae"] == 40 and d["ce"] == 5 and d["callsign"] == "HAMERITT-CHECK" and
              float(d["speed"]) == 1.5 and float(d["course"]) == 90 and
              d["remarks"] == "hameritt_tak_check event %d of %d" % (n + 1, EVENTS), d)
    check(name + ": every event arrives once", not missing_events(uids), missing_events(uids))


def refused(name, binary, pki, url, listener, args, reason, env=None, server_reason=None):
    p, s = run_check(binary, url, *args, seconds=1.0, env=env)
    errors = [ln for ln in p.stderr.splitlines() if ln.startswith("tak_check: error:")]
    check(name + ": exit 1", p.returncode == 1, "%d %s %s" % (p.returncode, p.stdout, p.stderr))
    check(name + ": the reason printed once", len(errors) == 1 and reason in errors[0],
          "want one line with %r: %s" % (reason, errors))
    check(name + ": retried, nothing sent", s is not None and s["sent"] == 0 and
          s["attempts"] >= 2 and s["connects"] == 0 and s["send_errors"] == 0 and s["dropped"] == 0 and
          # every attempt failed in TLS (the latest may still be in its handshake)
          1 <= s["attempts"] - 1 <= s["tls_failures"] <= s["attempts"],
          "%s %s" % (s, p.stdout))
    if listener is not None:
        listener.settle()
        check(name + ": the server got no event", not listener.events and not listener.frames,
              listener.events[:1])
        if server_reason:
            check(name + ": the server's reason", any(server_reason in e for e in listener.errors),
                  listener.errors)


def main():
    binary = os.path.join(os.environ.get("HAMERITT_BIN_DIR", ""), "hameritt_tak_check")
    source = os.environ.get("HAMERITT_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))))
    if not os.access(binary, os.X_OK):
        print("test_tak_tls: %s is not built ($HAMERITT_BIN_DIR)" % binary, file=sys.stderr)
        return 1
    build_dir = os.path.abspath(os.path.join(os.environ["HAMERITT_BIN_DIR"], "..", "..", ".."))
    node_prefix = install_node_cot(build_dir)
    if node_prefix is None:
        if os.environ.get("CI") == "true":
            print("test_tak_tls: FAIL: node-cot cannot be installed (CI=true)", file=sys.stderr)
            return 1
        print("test_tak_tls: skipped: node-cot cannot be installed (registry unreachable?)")
        return 77

    tmp = tempfile.mkdtemp(prefix="hameritt_tak_tls_")
    try:
        pki = os.path.join(tmp, "pki")
        subprocess.run(["bash", os.path.join(source, "test", "scripts", "tak_pki.sh"), pki], check=True)
        f = lambda n: os.path.join(pki, n)  # noqa: E731
        with open(f("ca.sha256")) as fp:
            ca_pin = fp.read().strip()
        with open(f("other-ca.sha256")) as fp:
            other_pin = fp.read().strip()
        pem = ["--client-cert", f("client.pem"), "--client-key", f("client-encrypted.key"),
               "--trust-store", f("ca.pem")]
        p12 = ["--client-p12", f("client.p12"), "--trust-store", f("truststore-root.p12")]
        pw = {"HAMERITT_TAK_CLIENT_PASSWORD": "atakatak", "HAMERITT_TAK_TRUST_PASSWORD": "trustpass"}

        # 1. PEM credentials, CoT XML.
        srv = Listener(pki)
        p, s = run_check(binary, "ssl://127.0.0.1:%d" % srv.port, *pem, env=pw)
        check("xml: exit 0", p.returncode == 0, p.stdout + p.stderr)
        check("xml: summary", s is not None and s["sent"] == EVENTS and s["events"] == EVENTS and
              s["encoding"] == "CoT XML" and s["connects"] == 1 and s["attempts"] == 1 and
              s["tls_failures"] == 0 and s["send_errors"] == 0 and s["dropped"] == 0, p.stdout)
        check("xml: connect logged", "tak_check: connected to ssl://127.0.0.1:%d (TLSv1" % srv.port in p.stdout,
              p.stdout)
        check("xml: the server read every connection to its end", srv.settle())
        check_xml_events("xml", srv.events)
        # Negative control of the arrival check: one event less is reported.
        check("control: a lost event is reported",
              missing_events(["hameritt.check.%d" % k for k in range(EVENTS - 1)]) == ["hameritt.check.%d" % (EVENTS - 1)])
        srv.close()

        # 2. PKCS#12 credentials and trust store, the CA pinned, TAK Protocol Version 1.
        srv = Listener(pki, negotiate=True)
        p, s = run_check(binary, "ssl://localhost:%d" % srv.port, *p12, "--pin-sha256", ca_pin,
                         "--encoding", "protobuf", env=pw)
        check("protobuf: exit 0", p.returncode == 0, p.stdout + p.stderr)
        check("protobuf: summary", s is not None and s["sent"] == EVENTS and
              s["encoding"] == "TAK Protocol Version 1" and s["connects"] == 1 and
              s["dropped"] == 0 and s["send_errors"] == 0, p.stdout)
        check("protobuf: the server read every connection to its end", srv.settle())
        check("protobuf: negotiated", srv.negotiated and not srv.events and not srv.errors,
              (srv.negotiated, srv.events[:1], srv.errors))
        stream_frames = list(srv.frames)
        srv.close()

        # 3. UDP mesh, TAK Protocol Version 1.
        rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        rx.bind(("127.0.0.1", 0))
        rx.settimeout(5)
        p, s = run_check(binary, "udp://127.0.0.1:%d" % rx.getsockname()[1], "--encoding", "protobuf")
        check("mesh: exit 0", p.returncode == 0 and s is not None and s["sent"] == EVENTS, p.stdout + p.stderr)
        datagrams = []
        try:
            for _ in range(EVENTS):
                datagrams.append(rx.recv(65536))
        except socket.timeout:
            pass
        rx.close()
        check("mesh: header 0xbf 0x01 0xbf", len(datagrams) == EVENTS and
              all(d[:3] == b"\xbf\x01\xbf" for d in datagrams), [d[:3] for d in datagrams])
        # One node run decodes them all (node-cot takes seconds to load): the stream's payloads,
        # the mesh's, and the negative control of the judge: a damaged payload (a length beyond
        # its end) must be rejected.
        mesh = [d[3:] for d in datagrams]
        bad = [stream_frames[0][:2] + bytes([0x7F]) + stream_frames[0][3:]] if stream_frames else []
        decoded = node_decode(node_prefix, stream_frames + mesh + bad)
        check_decoded("protobuf stream", decoded[:len(stream_frames)])
        check_decoded("mesh", decoded[len(stream_frames):len(stream_frames) + len(mesh)])
        check("control: node-cot rejects a damaged payload", bad and "error" in decoded[-1], decoded[-1:])

        # 4. Refusals: each reason printed once, retried, nothing sent.
        srv = Listener(pki, cert="other-server")
        refused("untrusted server", binary, pki, "ssl://127.0.0.1:%d" % srv.port, srv, pem,
                "server certificate rejected: unable to get local issuer certificate", env=pw,
                server_reason="UNKNOWN_CA")
        srv.close()
        srv = Listener(pki, cert="expired-server")
        refused("expired server certificate", binary, pki, "ssl://127.0.0.1:%d" % srv.port, srv, pem,
                "server certificate rejected: certificate has expired", env=pw,
                server_reason="CERTIFICATE_EXPIRED")
        srv.close()
        srv = Listener(pki)
        refused("no client certificate", binary, pki, "ssl://127.0.0.1:%d" % srv.port, srv,
                ["--trust-store", f("ca.pem")], "certificate required",
                server_reason="PEER_DID_NOT_RETURN_A_CERTIFICATE")
        refused("unknown client certificate", binary, pki, "ssl://127.0.0.1:%d" % srv.port, srv,
                ["--client-cert", f("other-client.pem"), "--client-key", f("other-client.key"),
                 "--trust-store", f("ca.pem")], "refused by the server", server_reason="CERTIFICATE_VERIFY_FAILED")
        refused("name mismatch", binary, pki, "ssl://127.0.0.1:%d" % srv.port, srv,
                pem + ["--server-name", "tak.example.org"], "does not name 'tak.example.org'", env=pw)
        refused("wrong pin", binary, pki, "ssl://127.0.0.1:%d" % srv.port, srv,
                pem + ["--pin-sha256", other_pin], "pinned SHA-256", env=pw)
        refused("wrong PKCS#12 password", binary, pki, "ssl://127.0.0.1:%d" % srv.port, srv, p12,
                "tls_client_p12 '%s': wrong password" % f("client.p12"),
                env={"HAMERITT_TAK_CLIENT_PASSWORD": "wrong", "HAMERITT_TAK_TRUST_PASSWORD": "trustpass"})
        srv.close()
        plain = Listener(pki, tls=False, close_at_once=True)
        refused("server closes the handshake", binary, pki, "ssl://127.0.0.1:%d" % plain.port, plain,
                pem, "closed the connection during the TLS handshake", env=pw)
        check("no plaintext: the server saw only TLS handshakes", plain.raw and
              all(r[:1] == b"\x16" and b"<event" not in r for r in plain.raw), [r[:8] for r in plain.raw])
        plain.close()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("test_tak_tls: %d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
