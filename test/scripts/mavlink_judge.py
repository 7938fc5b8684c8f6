"""An independent MAVLink decoder for the tests: written from MAVLink's serialization rules
(mavlink.io "Serialization") with Debian's python3-crcmod for the CRC-16/MCRF4XX, and the message
definitions of common.xml below. It shares no code or table with the simulator's codec: the
CRC_EXTRA bytes are derived here from the field lists, the way mavgen derives them.
"""
import struct

import crcmod.predefined

X25 = crcmod.predefined.mkCrcFun("crc-16-mcrf4xx")
SIZES = {"uint64_t": 8, "int64_t": 8, "double": 8, "float": 4, "uint32_t": 4, "int32_t": 4,
         "uint16_t": 2, "int16_t": 2, "uint8_t": 1, "int8_t": 1, "char": 1}
CODES = {"uint64_t": "Q", "int64_t": "q", "double": "d", "float": "f", "uint32_t": "I",
         "int32_t": "i", "uint16_t": "H", "int16_t": "h", "uint8_t": "B", "int8_t": "b",
         "char": "c"}

# common.xml: id -> (name, base fields in declaration order, extension fields).
# A field is "type name" or "type name[N]".
DEFINITIONS = {
    0: ("HEARTBEAT", ["uint8_t type", "uint8_t autopilot", "uint8_t base_mode",
                      "uint32_t custom_mode", "uint8_t system_status",
                      "uint8_t mavlink_version"], []),
    2: ("SYSTEM_TIME", ["uint64_t time_unix_usec", "uint32_t time_boot_ms"], []),
    30: ("ATTITUDE", ["uint32_t time_boot_ms", "float roll", "float pitch", "float yaw",
                      "float rollspeed", "float pitchspeed", "float yawspeed"], []),
    33: ("GLOBAL_POSITION_INT", ["uint32_t time_boot_ms", "int32_t lat", "int32_t lon",
                                 "int32_t alt", "int32_t relative_alt", "int16_t vx",
                                 "int16_t vy", "int16_t vz", "uint16_t hdg"], []),
    76: ("COMMAND_LONG", ["uint8_t target_system", "uint8_t target_component",
                          "uint16_t command", "uint8_t confirmation"] +
         ["float param%d" % i for i in range(1, 8)], []),
    77: ("COMMAND_ACK", ["uint16_t command", "uint8_t result"],
         ["uint8_t progress", "int32_t result_param2", "uint8_t target_system",
          "uint8_t target_component"]),
    93: ("HIL_ACTUATOR_CONTROLS", ["uint64_t time_usec", "float controls[16]", "uint8_t mode",
                                   "uint64_t flags"], []),
    107: ("HIL_SENSOR", ["uint64_t time_usec"] +
          ["float " + n for n in "xacc yacc zacc xgyro ygyro zgyro xmag ymag zmag abs_pressure "
                                 "diff_pressure pressure_alt temperature".split()] +
          ["uint32_t fields_updated"], ["uint8_t id"]),
    113: ("HIL_GPS", ["uint64_t time_usec", "uint8_t fix_type", "int32_t lat", "int32_t lon",
                      "int32_t alt", "uint16_t eph", "uint16_t epv", "uint16_t vel",
                      "int16_t vn", "int16_t ve", "int16_t vd", "uint16_t cog",
                      "uint8_t satellites_visible"], ["uint8_t id", "uint16_t yaw"]),
    115: ("HIL_STATE_QUATERNION", ["uint64_t time_usec", "float attitude_quaternion[4]",
                                   "float rollspeed", "float pitchspeed", "float yawspeed",
                                   "int32_t lat", "int32_t lon", "int32_t alt", "int16_t vx",
                                   "int16_t vy", "int16_t vz", "uint16_t ind_airspeed",
                                   "uint16_t true_airspeed", "int16_t xacc", "int16_t yacc",
                                   "int16_t zacc"], []),
}


def _parse_field(text):
    ftype, name = text.split()
    count = 0
    if "[" in name:
        name, n = name[:-1].split("[")
        count = int(n)
    return ftype, name, count


class Message:
    def __init__(self, msgid, name, base, ext):
        self.id = msgid
        self.name = name
        fields = [_parse_field(f) for f in base]
        # Wire order: base fields sorted by type size (stable), then extensions as declared.
        self.wire = sorted(fields, key=lambda f: -SIZES[f[0]]) + [_parse_field(f) for f in ext]
        self.base_len = sum(SIZES[t] * max(1, n) for t, _, n in sorted(fields))
        self.full_len = sum(SIZES[t] * max(1, n) for t, _, n in self.wire)
        crc = X25((name + " ").encode())
        for t, n, count in sorted(fields, key=lambda f: -SIZES[f[0]]):
            crc = X25((t + " ").encode(), crc)
            crc = X25((n + " ").encode(), crc)
            if count:
                crc = X25(bytes([count]), crc)
        self.crc_extra = (crc & 0xFF) ^ (crc >> 8)
        self.fmt = "<" + "".join(("%d" % n if n else "") + CODES[t] for t, _, n in self.wire)

    def decode(self, payload):
        values = struct.unpack(self.fmt, payload + bytes(self.full_len - len(payload)))
        out, i = {}, 0
        for t, n, count in self.wire:
            if count:
                out[n] = list(values[i:i + count])
                i += count
            else:
                out[n] = values[i]
                i += 1
        return out

    def encode(self, seq, sysid, compid, **fields):
        values = []
        for t, n, count in self.wire:
            v = fields.get(n, [0] * count if count else 0)
            values.extend(v if count else [v])
        payload = struct.pack(self.fmt, *values)
        end = len(payload)
        while end > 1 and payload[end - 1] == 0:
            end -= 1
        payload = payload[:end]
        header = bytes([0xFD, len(payload), 0, 0, seq & 0xFF, sysid, compid]) + \
            struct.pack("<I", self.id)[:3]
        crc = X25(bytes([self.crc_extra]), X25(header[1:] + payload))
        return header + payload + struct.pack("<H", crc)


MESSAGES = {i: Message(i, *d) for i, d in DEFINITIONS.items()}
BY_NAME = {m.name: m for m in MESSAGES.values()}


def encode(name, seq=0, sysid=255, compid=190, **fields):
    return BY_NAME[name].encode(seq, sysid, compid, **fields)


class Decoder:
    """Streams bytes into frames; counts what it skips. strict=True: nothing but valid frames
    may appear (the simulator's output must be all frames)."""

    def __init__(self):
        self.buf = bytearray()
        self.frames = 0
        self.stray = 0
        self.bad_crc = 0
        self.unknown = 0
        self.truncated = 0
        self.by_name = {}

    def drop_partial(self):
        """Gives up on the partial frames held (their sender stopped mid-frame), as the
        simulator does when no byte follows for 0.1 s."""
        out = []
        while self.buf:
            self.truncated += 1
            del self.buf[0]
            out += self.feed(b"")
        return out

    def feed(self, data):
        self.buf += data
        buf, at, end, out = self.buf, 0, len(self.buf), []
        while at < end:
            stx = buf[at]
            if stx not in (0xFD, 0xFE):
                self.stray += 1
                at += 1
                continue
            hlen = 10 if stx == 0xFD else 6
            if end - at < hlen:
                break
            n = buf[at + 1]
            signed = stx == 0xFD and (buf[at + 2] & 1)
            total = hlen + n + 2 + (13 if signed else 0)
            if end - at < total:
                break
            if stx == 0xFD:
                msgid = buf[at + 7] | (buf[at + 8] << 8) | (buf[at + 9] << 16)
                seq, sysid, compid = buf[at + 4], buf[at + 5], buf[at + 6]
            else:
                msgid, seq, sysid, compid = buf[at + 5], buf[at + 2], buf[at + 3], buf[at + 4]
            m = MESSAGES.get(msgid)
            if m is None:
                self.unknown += 1
                at += 1
                continue
            crc = X25(bytes([m.crc_extra]), X25(bytes(buf[at + 1:at + hlen + n])))
            got = buf[at + hlen + n] | (buf[at + hlen + n + 1] << 8)
            if crc != got:
                self.bad_crc += 1
                at += 1
                continue
            payload = bytes(buf[at + hlen:at + hlen + n])
            at += total
            self.frames += 1
            self.by_name[m.name] = self.by_name.get(m.name, 0) + 1
            out.append((m.name, seq, sysid, compid, m.decode(payload)))
        del self.buf[:at]
        return out


def self_check():
    """Known answers this decoder must reproduce (its own controls)."""
    assert X25(b"123456789") == 0x6F91
    published = {"HEARTBEAT": 50, "SYSTEM_TIME": 137, "HIL_SENSOR": 108, "HIL_GPS": 124,
                 "HIL_STATE_QUATERNION": 4, "HIL_ACTUATOR_CONTROLS": 47, "COMMAND_LONG": 152,
                 "ATTITUDE": 39, "GLOBAL_POSITION_INT": 104, "COMMAND_ACK": 143}
    for name, extra in published.items():
        assert BY_NAME[name].crc_extra == extra, (name, BY_NAME[name].crc_extra, extra)
    # The hand-worked HEARTBEAT frame (see test/sitl/mavlink_test.cpp).
    hb = bytes.fromhex("FD09000000010100000000000000020C81040363 8C".replace(" ", ""))
    d = Decoder()
    frames = d.feed(hb)
    assert len(frames) == 1 and frames[0][4]["autopilot"] == 12, frames
    bad = bytearray(hb)
    bad[14] ^= 1
    d2 = Decoder()
    assert not d2.feed(bytes(bad)) and d2.bad_crc == 1  # negative control
    return len(published)
