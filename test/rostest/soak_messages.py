"""Random input for the soak (test_soak.py), from one random.Random: images of
random sizes, encodings, steps and contents (NaN, inf, negative depth), and
any ROS message filled at random field by field (NaN/inf floats, arrays of
unrelated lengths, random strings and stamps).

Each image comes with `broken`: True if its layout alone makes every node
refuse it (unknown encoding, zero size, step or data too short), which the
soak checks is counted as a drop."""
import math
import struct

import genpy
from sensor_msgs.msg import Image

# bytes per pixel of the encodings the nodes know (node_common.cpp)
BPP = {"32FC1": 4, "16UC1": 2, "rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4, "mono8": 1}
DEPTH = ("32FC1", "16UC1")
COLOUR = ("rgb8", "bgr8", "rgba8", "bgra8", "mono8")
OTHER = ("8UC3", "32FC3", "16SC1", "mono16", "bogus", "", "32fc1")
W, H = 320, 240  # the camera of config/semantic.yaml
SPECIAL_FLOATS = (float("nan"), float("inf"), -float("inf"), 0.0, -1.0, 1e30, -1e30, 5e-324)
MAX_BYTES = 4 << 20  # keeps one message at most 4 MB


def stamp(rng, base_s):
    """A stamp near base_s, at times 0, or before earlier ones (stamps going backwards)."""
    r = rng.random()
    if r < 0.05:
        return genpy.Time(0, 0)
    if r < 0.25:
        return genpy.Time.from_sec(max(0.0, base_s - rng.uniform(0.0, 100.0)))
    return genpy.Time.from_sec(base_s + rng.uniform(0.0, 0.5))


def image(rng, encodings, stamp_, frame_id="camera"):
    """(Image, broken) with an encoding from `encodings` (those the topic
    takes) most of the time; broken: the layout is unusable whatever the
    node's state."""
    m = Image()
    m.header.stamp = stamp_
    m.header.frame_id = rng.choice([frame_id] * 8 + ["", "nowhere"])
    r = rng.random()
    m.encoding = rng.choice(encodings) if r < 0.8 else rng.choice(OTHER + DEPTH + COLOUR)
    size = rng.random()
    if size < 0.5:
        m.width, m.height = W, H
    elif size < 0.6:
        m.width, m.height = rng.choice([(0, 0), (0, H), (W, 0)])
    elif size < 0.7:
        m.width, m.height = rng.choice([(100000, 100000), (65535, 1), (1, 65535), (2 ** 32 - 1, 2)])
    else:
        m.width, m.height = rng.randint(1, 640), rng.randint(1, 480)
    bpp = BPP.get(m.encoding, 1)
    row = m.width * bpp
    s = rng.random()
    if s < 0.7:
        m.step = row
    elif s < 0.8:
        m.step = row + rng.randint(1, 64)  # padded rows
    elif s < 0.9:
        m.step = max(0, row - rng.randint(1, 8))  # rows too short
    else:
        m.step = rng.choice([0, 1, 2 ** 32 - 1])
    m.step = min(m.step, 2 ** 32 - 1)  # a uint32
    m.is_bigendian = rng.random() < 0.05
    want = m.step * m.height
    d = rng.random()
    if d < 0.75:
        n = want
    elif d < 0.85:
        n = max(0, want - rng.randint(1, max(1, want)))  # cut short
    elif d < 0.95:
        n = want + rng.randint(1, 4096)  # trailing bytes
    else:
        n = 0
    n = min(n, MAX_BYTES)
    m.data = _pixels(rng, m.encoding, n)
    broken = (m.encoding not in encodings or m.width == 0 or m.height == 0 or m.step < row or len(m.data) < want
              or m.is_bigendian)
    return m, broken


def _pixels(rng, encoding, n):
    """n bytes of plausible pixels: depth in metres with NaN/inf/negative
    values, millimetres, or random bytes."""
    if encoding == "32FC1" and n >= 4:
        k = n // 4
        base = rng.uniform(0.05, 12.0)
        vals = [base] * k
        for _ in range(min(k, 200)):  # a sprinkling of special values
            vals[rng.randrange(k)] = rng.choice(SPECIAL_FLOATS)
        return struct.pack("<%df" % k, *vals) + bytes(n - 4 * k)
    seed = rng.getrandbits(32)
    out = bytearray(n)
    for i in range(0, n, 4096):  # cheap: a few random bytes repeated
        chunk = (seed * (i + 1)) & 0xFFFFFFFF
        out[i:i + 4] = chunk.to_bytes(4, "little")[:max(0, min(4, n - i))]
    return bytes(out)


def _number(rng, t):
    if t in ("float32", "float64"):
        return rng.choice(SPECIAL_FLOATS) if rng.random() < 0.4 else rng.uniform(-1e3, 1e3)
    if t == "bool":
        return rng.random() < 0.5
    bits = int("".join(c for c in t if c.isdigit()) or 8)
    if t.startswith("u") or t in ("byte", "char"):
        hi = 2 ** bits - 1
        return rng.choice([0, 1, hi, rng.randint(0, hi), rng.randint(0, min(hi, 1000))])
    lo, hi = -2 ** (bits - 1), 2 ** (bits - 1) - 1
    return rng.choice([0, -1, lo, hi, rng.randint(lo, hi), rng.randint(-1000, 1000)])


def _value(rng, t, depth):
    if t.endswith("]"):
        base, n = t[:t.index("[")], t[t.index("[") + 1:-1]
        count = int(n) if n else rng.choice([0, 1, 2, 3, rng.randint(0, 50)])
        if base in ("uint8", "char", "byte"):
            count = int(n) if n else rng.choice([0, 1, 7, 12, 13, rng.randint(0, 20000)])
            return bytes(rng.getrandbits(8) for _ in range(min(count, 64))) + bytes(max(0, count - 64))
        return [_value(rng, base, depth + 1) for _ in range(count)]
    if t == "string":
        return rng.choice(["", "chair", "camera", "world", "x", "\u00e9\u00e8", "a" * rng.randint(0, 300)])
    if t == "time":
        return genpy.Time(rng.randint(0, 2 ** 31), rng.randint(0, 999999999))
    if t == "duration":
        return genpy.Duration(rng.randint(-2 ** 31, 2 ** 31 - 1), rng.randint(0, 999999999))
    if t in ("bool", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "float32", "float64",
             "byte", "char"):
        return _number(rng, t)
    if t == "Header":
        t = "std_msgs/Header"
    return fill(rng, genpy.message.get_message_class(t)(), depth + 1)


def fill(rng, msg, depth=0):
    """msg with every field random (in place); nested messages recursively."""
    for name, t in zip(msg.__slots__, msg._slot_types):
        if depth > 4 and t.endswith("[]"):
            setattr(msg, name, [] if not t.startswith(("uint8", "char", "byte")) else b"")
            continue
        setattr(msg, name, _value(rng, t, depth))
    return msg


def finite(v):
    return isinstance(v, float) and math.isfinite(v)
