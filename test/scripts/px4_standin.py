"""A stand-in for PX4 SITL (Python standard library plus the tests' independent MAVLink decoder):
it does what PX4's simulator_mavlink module does on connect (HEARTBEAT, SET_MESSAGE_INTERVAL for
HIL_STATE_QUATERNION), checks each HIL_SENSOR (the fields_updated masks, time advancing by
exactly one sensor period, the at-rest specific force and the origin's standard-atmosphere
pressure), estimates its state from the IMU, magnetometer, barometer and GPS alone (never the
simulator's ground truth) and flies the quadrotor with its own PID loops, answering every
HIL_SENSOR with one HIL_ACTUATOR_CONTROLS (lock-step).

Vehicle constants it assumes, as an autopilot's airframe configuration would: the mass, the rotor
constant kf, the arm length and the maximum rotor speed (a control of 1) of models/sentinel.urdf.
"""
import math
import socket
import time

import mavlink_judge as mj

G = 9.80665
MASK_ALL = 0x7 | 0x38 | 0x1C0 | 0x200 | 0x800 | 0x1000
ARMED = 128


def isa_pressure_hpa(h):
    return 1013.25 * (1.0 - 0.0065 * h / 288.15) ** 5.255877


def quat_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def quat_rotate(q, v):
    w, x, y, z = q
    p = quat_mul(quat_mul(q, (0.0, v[0], v[1], v[2])), (w, -x, -y, -z))
    return p[1], p[2], p[3]


def clamp(v, lo, hi):
    return max(lo, min(hi, v))


class Estimator:
    """Attitude from gyro integration with a small accelerometer tilt correction (Mahony) and the
    magnetometer for heading; height and climb rate from the barometer fused with the vertical
    acceleration; horizontal velocity and position from the GPS."""

    def __init__(self, mag_ned):
        self.q = (1.0, 0.0, 0.0, 0.0)  # FRD -> NED
        self.h = 0.0
        self.vz = 0.0  # up
        self.baro0 = None
        self.baro_n = 0
        self.baro_sum = 0.0
        self.heading_init = False
        self.mag_decl = math.atan2(mag_ned[1], mag_ned[0])
        self.vel_ne = (0.0, 0.0)
        self.pos_ne = None
        self.origin = None

    def update(self, s, dt, landed):
        gyro = (s["xgyro"], s["ygyro"], s["zgyro"])
        acc = (s["xacc"], s["yacc"], s["zacc"])
        if not self.heading_init:
            # Level at rest: the heading from the horizontal magnetic field.
            yaw = math.atan2(-s["ymag"], s["xmag"]) + self.mag_decl
            self.q = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
            self.heading_init = True
        # Tilt correction: the specific force points up (FRD -z at rest) against the estimated
        # up direction.
        n = math.sqrt(sum(a * a for a in acc)) or 1.0
        up_meas = tuple(a / n for a in acc)
        w, x, y, z = self.q
        up_est = quat_rotate((w, -x, -y, -z), (0.0, 0.0, -1.0))
        err = (up_meas[1] * up_est[2] - up_meas[2] * up_est[1],
               up_meas[2] * up_est[0] - up_meas[0] * up_est[2],
               up_meas[0] * up_est[1] - up_meas[1] * up_est[0])
        k = 1.0 if landed else 0.2
        wx, wy, wz = (gyro[i] + k * err[i] for i in range(3))
        dq = quat_mul(self.q, (0.0, wx, wy, wz))
        q = tuple(self.q[i] + 0.5 * dq[i] * dt for i in range(4))
        qn = math.sqrt(sum(c * c for c in q))
        self.q = tuple(c / qn for c in q)
        # Height: barometer relative to its value on the ground, fused with the acceleration.
        baro_h = s["pressure_alt"]
        if self.baro0 is None or (landed and self.baro_n < 250):
            self.baro_sum += baro_h
            self.baro_n += 1
            self.baro0 = self.baro_sum / self.baro_n
        a_ned = quat_rotate(self.q, acc)
        a_up = -(a_ned[2] + G)
        self.vz += a_up * dt
        self.h += self.vz * dt
        e = (baro_h - self.baro0) - self.h
        self.h += 2.0 * e * dt
        self.vz += 1.0 * e * dt
        if landed:
            self.vz *= 0.9

    def gps(self, g):
        lat, lon = g["lat"] * 1e-7, g["lon"] * 1e-7
        if self.origin is None:
            self.origin = (lat, lon)
        r = 6378137.0
        n = math.radians(lat - self.origin[0]) * r
        e = math.radians(lon - self.origin[1]) * r * math.cos(math.radians(self.origin[0]))
        self.pos_ne = (n, e)
        self.vel_ne = (g["vn"] / 100.0, g["ve"] / 100.0)

    def euler(self):
        w, x, y, z = self.q
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(clamp(2 * (w * y - z * x), -1.0, 1.0))
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        return roll, pitch, yaw


class Autopilot:
    """The flight: on the ground disarmed for `idle_s`, arm, climb to `altitude` at 1.5 m/s,
    hold for `hold_s`, descend at 0.6 m/s, disarm once landed. `stall_at_s` (sim time, during the
    hold): stop answering for `stall_wall_s` wall seconds once."""

    def __init__(self, port, mass=1.04, kf=1.3e-6, km=2.08e-8, arm=0.15, max_speed=2600.0,
                 inertia=(0.00544, 0.00544, 0.0100), mag_ned=(0.21, -0.01, 0.42),
                 origin_alt=40.0, altitude=10.0, hold_s=34.0, idle_s=1.0, stall_at_s=None,
                 stall_wall_s=2.0, before_arm=None, log=print):
        if port is not None:
            self.sock = socket.create_connection(("127.0.0.1", port), timeout=30)
            self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.decoder = mj.Decoder()
        self.sent = bytearray()  # every byte this client sent (for the judge's replay)
        self.seq = 0
        self.m, self.kf, self.km, self.max_speed = mass, kf, km, max_speed
        self.arm_xy = arm / math.sqrt(2.0)
        self.inertia = inertia
        self.origin_alt = origin_alt
        self.altitude, self.hold_s, self.idle_s = altitude, hold_s, idle_s
        self.stall_at_s, self.stall_wall_s = stall_at_s, stall_wall_s
        self.before_arm = before_arm
        self.log = log
        self.est = Estimator(mag_ned)
        self.problems = []
        self.sensors = 0
        self.last_t = None
        self.phase = "idle"
        self.phase_t = 0.0
        self.armed = False
        self.was_armed = False
        self.h_sp = 0.0
        self.vz_int = 0.0
        self.rate_int = [0.0, 0.0, 0.0]
        self.stalled = None  # (sim time, wall seconds)
        self.received = {}
        self.landed_for = 0.0
        self.hold_start = None
        self.done = False
        self.step_us = None
        self.t0 = None  # sim time of the first HIL_SENSOR
        self.truth = None
        self.trace = []
        self.first_t = None

    # -------------------------------------------------------------------------- wire
    def send(self, name, **fields):
        frame = mj.encode(name, self.seq, 1, 1, **fields)
        self.seq = (self.seq + 1) & 0xFF
        self.send_raw(frame)

    def send_raw(self, data):
        self.sent += data
        self.sock.sendall(data)

    def connect_handshake(self):
        self.send("HEARTBEAT", type=2, autopilot=12, base_mode=0, custom_mode=0,
                  system_status=3, mavlink_version=3)
        self.send("COMMAND_LONG", target_system=1, target_component=51, command=511,
                  param1=115.0, param2=20000.0)

    def frames(self):
        data = self.sock.recv(65536)
        if not data:
            raise ConnectionError("the simulator closed the connection")
        return self.decoder.feed(data)

    # ------------------------------------------------------------------------ checks
    def check(self, ok, what):
        if not ok and len(self.problems) < 20:
            self.problems.append(what)

    def check_sensor(self, s, at_rest):
        self.check(s["fields_updated"] & MASK_ALL == MASK_ALL,
                   "HIL_SENSOR fields_updated 0x%x lacks 0x%x" % (s["fields_updated"], MASK_ALL))
        t = s["time_usec"]
        if self.first_t is None:
            self.first_t = t
        if self.last_t is not None:
            step = t - self.last_t
            if self.step_us is None:
                self.step_us = step
            self.check(step == self.step_us,
                       "HIL_SENSOR time advanced by %d us, expected %s" % (step, self.step_us))
        self.last_t = t
        if at_rest:
            self.check(abs(s["zacc"] + G) < 0.5, "at rest zacc %.3f, expected about -9.81" % s["zacc"])
            expected = isa_pressure_hpa(self.origin_alt)
            self.check(abs(s["abs_pressure"] - expected) < 0.1,
                       "at rest pressure %.3f hPa, expected %.3f (ISA at %.0f m)" % (
                           s["abs_pressure"], expected, self.origin_alt))

    # ----------------------------------------------------------------------- control
    def controls(self, dt, t):
        est = self.est
        roll, pitch, yaw = est.euler()
        if self.phase == "idle":
            if t - self.t0 >= self.idle_s:
                if self.before_arm:
                    self.before_arm(self)
                self.phase, self.armed, self.was_armed = "climb", True, True
                self.log("stand-in: armed at sim %.3f s" % t)
            return [0.0] * 4
        if self.phase == "climb":
            self.h_sp = min(self.altitude, self.h_sp + 1.5 * dt)
            if est.h > self.altitude - 0.2:
                self.phase, self.hold_start = "hold", t
                self.log("stand-in: holding %.1f m from sim %.3f s" % (self.altitude, t))
        elif self.phase == "hold":
            self.h_sp = self.altitude
            if t - self.hold_start >= self.hold_s:
                self.phase = "descend"
                self.log("stand-in: descending at sim %.3f s" % t)
        elif self.phase == "descend":
            self.h_sp -= 0.6 * dt
            near_ground = est.h < 0.5
            still = abs(est.vz) < 0.25
            self.landed_for = self.landed_for + dt if (near_ground and still and self.h_sp < 0) else 0.0
            if self.landed_for > 1.0:
                self.phase, self.armed = "landed", False
                self.log("stand-in: landed, disarmed at sim %.3f s" % t)
        if self.phase == "landed":
            self.done = True
            return [0.0] * 4
        # Vertical: height P -> climb-rate PI -> collective thrust.
        vz_sp = clamp(1.2 * (self.h_sp - est.h), -0.8, 1.5)
        if self.phase == "descend":
            vz_sp = max(vz_sp, -0.6)
        ev = vz_sp - est.vz
        self.vz_int = clamp(self.vz_int + 1.5 * ev * dt, -3.0, 3.0)
        a_up = 3.0 * ev + self.vz_int
        tilt = max(0.5, math.cos(roll) * math.cos(pitch))
        thrust = self.m * (G + a_up) / tilt
        # Horizontal: hold the GPS position where it took off (velocity damping).
        an, ae = 0.0, 0.0
        if est.pos_ne is not None:
            an = 0.3 * (0.0 - est.pos_ne[0]) - 1.0 * est.vel_ne[0]
            ae = 0.3 * (0.0 - est.pos_ne[1]) - 1.0 * est.vel_ne[1]
        pitch_sp = clamp(-(an * math.cos(yaw) + ae * math.sin(yaw)) / G, -0.25, 0.25)
        roll_sp = clamp((-an * math.sin(yaw) + ae * math.cos(yaw)) / G, -0.25, 0.25)
        on_ground = est.h < 0.3
        if on_ground:
            # Integrators and horizontal hold frozen until airborne (the ground holds the body).
            roll_sp = pitch_sp = 0.0
            self.rate_int = [0.0, 0.0, 0.0]
        # Attitude P -> body-rate PI -> torques (FRD).
        rate_sp = (6.0 * (roll_sp - roll), 6.0 * (pitch_sp - pitch), 0.0)
        gyro = self.gyro
        gains = (20.0, 20.0, 10.0)
        torque = []
        for i in range(3):
            e = rate_sp[i] - gyro[i]
            self.rate_int[i] = clamp(self.rate_int[i] + 5.0 * e * dt, -5.0, 5.0)
            torque.append(self.inertia[i] * (gains[i] * e + self.rate_int[i]))
        return self.mix(thrust, torque)

    def mix(self, thrust, torque):
        """Quad-X outputs: 1 front-right ccw, 2 rear-left ccw, 3 front-left cw, 4 rear-right cw.
        FRD: rotor i at (x, y) gives roll torque -y*T and pitch torque x*T; a ccw rotor's drag
        turns the body about +z (down) by km/kf * T."""
        l, k = self.arm_xy, self.km / self.kf
        signs = [(-1, 1, 1), (1, -1, 1), (1, 1, -1), (-1, -1, -1)]  # (roll, pitch, yaw) signs
        out = []
        for a, b, d in signs:
            t = thrust / 4 + a * torque[0] / (4 * l) + b * torque[1] / (4 * l) + d * torque[2] / (4 * k)
            w = math.sqrt(max(t, 0.0) / self.kf)
            out.append(clamp(w / self.max_speed, 0.0, 1.0))
        return out

    # -------------------------------------------------------------------------- loop
    def run(self, max_wall_s=300.0):
        """Flies until landed and disarmed; returns the sim time it ended at."""
        self.connect_handshake()
        start = time.time()
        t = 0.0
        while not self.done and time.time() - start < max_wall_s:
            for name, _, _, _, f in self.frames():
                self.received[name] = self.received.get(name, 0) + 1
                if name == "HIL_GPS":
                    self.est.gps(f)
                elif name == "HIL_STATE_QUATERNION":
                    # Ground truth: recorded beside the estimate for the report, never flown on.
                    self.truth = f
                elif name == "HIL_SENSOR":
                    t = f["time_usec"] * 1e-6
                    if self.t0 is None:
                        self.t0 = t
                    dt = (self.step_us or 4000) * 1e-6
                    at_rest = self.phase == "idle"
                    self.check_sensor(f, at_rest)
                    self.gyro = (f["xgyro"], f["ygyro"], f["zgyro"])
                    self.est.update(f, dt, landed=self.phase in ("idle", "landed"))
                    c = self.controls(dt, t)
                    if (self.stall_at_s is not None and self.stalled is None and
                            self.phase == "hold" and t >= self.stall_at_s):
                        self.stalled = (t, self.stall_wall_s)
                        self.log("stand-in: stalling %.1f wall s at sim %.3f s" % (self.stall_wall_s, t))
                        time.sleep(self.stall_wall_s)
                    self.send("HIL_ACTUATOR_CONTROLS", time_usec=f["time_usec"],
                              controls=c + [0.0] * 12, mode=ARMED if self.armed else 0, flags=1)
                    self.sensors += 1
                    if self.sensors % 125 == 0 and self.truth is not None:
                        r, p, _ = self.est.euler()
                        q = self.truth["attitude_quaternion"]
                        self.trace.append((round(t, 2), self.phase, round(self.h_sp, 2),
                                           round(self.est.h, 2), round(self.est.vz, 2),
                                           round(self.truth["alt"] / 1000.0 - self.origin_alt, 2),
                                           round(-self.truth["vz"] / 100.0, 2), round(r, 3),
                                           round(p, 3), [round(c, 3) for c in q]))
        return t

    def close(self):
        """Closes as an autopilot that exits cleanly: no more sends (FIN), then what the simulator
        still sends is read until it closes too (at most 2 s). A socket closed with unread bytes
        sends a reset, and the kernel drops what it still holds of our last frames: the
        simulator's counters then missed them (seen on a loaded machine: 8 actuator frames)."""
        try:
            self.sock.shutdown(socket.SHUT_WR)
            self.sock.settimeout(0.2)
            end = time.time() + 2.0
            while time.time() < end:
                try:
                    if not self.sock.recv(65536):
                        break
                except socket.timeout:
                    continue
        except OSError:
            pass
        self.sock.close()
