"""The MAVLink 2 frames battsim's telemetry sends, read back for the scripts (standard library
only): the bitwise CRC-16/MCRF4XX, written apart from src/telemetry's byte-wise one, and the
frames of a raw stream or a .tlog, each checked."""
import struct

CRC_EXTRA = {0: 50, 147: 154, 253: 83}  # HEARTBEAT, BATTERY_STATUS, STATUSTEXT
FULL_LENGTH = {0: 9, 147: 54, 253: 54}
# BATTERY_STATUS as on the wire (fields by size, then the extensions in order).
BATTERY_STATUS = "<iih10HhBBBbiB4HBI"


def crc(data, c=0xFFFF):
    for b in data:
        c ^= b
        for _ in range(8):
            c = (c >> 1) ^ 0x8408 if c & 1 else c >> 1
    return c


def frames(data, tlog=False):
    """(time_s or None, msgid, payload zero-filled to its full length) per frame; ValueError on a bad one."""
    out, i = [], 0
    while i < len(data):
        t = None
        if tlog:
            t = struct.unpack_from(">Q", data, i)[0] * 1e-6
            i += 8
        if data[i] != 0xFD:
            raise ValueError("no frame at byte %d" % i)
        n = data[i + 1]
        msgid = data[i + 7] | data[i + 8] << 8 | data[i + 9] << 16
        if msgid not in CRC_EXTRA:
            raise ValueError("unknown message %d at byte %d" % (msgid, i))
        if crc(data[i + 1:i + 10 + n] + bytes([CRC_EXTRA[msgid]])) != struct.unpack_from("<H", data, i + 10 + n)[0]:
            raise ValueError("bad checksum at byte %d" % i)
        out.append((t, msgid, data[i + 10:i + 10 + n] + bytes(FULL_LENGTH[msgid] - n)))
        i += 12 + n
    return out


def text(payload):
    """A STATUSTEXT payload's sentence."""
    return payload[1:51].split(b"\0")[0].decode()
