"""A stand-in for ArduPilot SITL's JSON interface (Python standard library): it sends one
40-byte servo packet per frame (magic 18458, frame rate, frame count, 16 PWM values) over UDP and
flies with the PX4 stand-in's estimator and PID (px4_standin.Autopilot) on what each JSON line
gives it: the IMU, and the position and velocity that ArduPilot turns into its GPS and
barometer. Checks each line: one sensor period of timestamp per new frame, the same line again
for a repeated frame count.
"""
import json
import math
import socket
import struct

import px4_standin

MAGIC = 18458


def servo_packet(frame, pwm, rate=250, magic=MAGIC):
    return struct.pack("<HHI16H", magic, rate, frame, *pwm)


class ArduPilotStandin(px4_standin.Autopilot):
    def __init__(self, port, **kw):
        super().__init__(None, **kw)
        self.udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.udp.settimeout(2.0)
        self.addr = ("127.0.0.1", port)
        self.frame = 0
        self.pwm = [1000] * 16
        self.lines = 0
        self.bad_lines = 0
        self.last_ts = None

    def exchange(self, frame=None, raw=None):
        """Sends a servo packet (or `raw` bytes) and returns the parsed JSON reply."""
        self.udp.sendto(raw if raw is not None else servo_packet(
            self.frame if frame is None else frame, self.pwm), self.addr)
        data, _ = self.udp.recvfrom(65536)
        text = data.decode()
        self.check(text.startswith("\n") and text.endswith("\n") and text.count("\n") == 2,
                   "a JSON reply that is not one line: %r" % text[:80])
        self.lines += 1
        return json.loads(text)

    def feed(self, j):
        """The estimator's inputs from a JSON line (FRD IMU, NED position and velocity)."""
        g, a = j["imu"]["gyro"], j["imu"]["accel_body"]
        n, e, d = j["position"]
        s = {"xgyro": g[0], "ygyro": g[1], "zgyro": g[2], "xacc": a[0], "yacc": a[1],
             "zacc": a[2], "pressure_alt": self.origin_alt - d}
        if not self.est.heading_init:
            w, x, y, z = j["quaternion"]
            yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
            self.est.q = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
            self.est.heading_init = True
        return s

    def run_udp(self, max_frames=200000, stall_hook=None):
        t = 0.0
        while not self.done and self.frame < max_frames:
            j = self.exchange()
            t = j["timestamp"]
            if self.last_ts is not None:
                self.check(abs(t - self.last_ts - 0.004) < 1e-9,
                           "timestamp advanced by %.6f s, expected 0.004" % (t - self.last_ts))
            self.last_ts = t
            if self.t0 is None:
                self.t0 = t
            if self.first_t is None:
                self.first_t = int(round(t * 1e6))
            self.last_t = int(round(t * 1e6))
            s = self.feed(j)
            n, e, d = j["position"]
            if self.est.origin is None:
                self.est.origin = (0.0, 0.0)
                self.start_ne = (n, e)
            self.est.pos_ne = (n - self.start_ne[0], e - self.start_ne[1])
            self.est.vel_ne = (j["velocity"][0], j["velocity"][1])
            self.gyro = (s["xgyro"], s["ygyro"], s["zgyro"])
            self.est.update(s, 0.004, landed=self.phase in ("idle", "landed"))
            c = self.controls(0.004, t)
            self.pwm = [int(round(1000 + 1000 * v)) if self.armed else 1000 for v in c] + [1000] * 12
            if stall_hook:
                stall_hook(self, t)
            self.frame += 1
            self.sensors += 1
        return t
