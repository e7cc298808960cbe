#!/usr/bin/env python3
"""Regenerates the seed corpora in test/fuzz/corpus/ from the repository's real files.

trc/:          arm26_elbow_flex.trc whole, the other real TRC files cut to their first rows.
structure/:    the structure-selection sweep's windows (scripts/sweep-structure) of the real TRC
               captures and the crash reproducer (test/data/crash): 40 and 80 frames at the start
               and the end, the first 6 markers (what fuzz_structure selects on).
c3d/:          the real C3D files with the data cut to ~20 KB and the header's last frame set to
               match (so they still parse and the fuzzer starts inside the data loop), plus the
               whole Sample02 files (< 100 KB).
model_yaml/:   the scene model files config/models/*.yaml (the big ones thinned to a few
               particles and the bonds between them) and the short example of docs/model_file.md,
               extended by hand with a free gravity, groups, conditions, flexion, viscosity and
               an interaction (written out below, not read from the page; the seed file keeps
               its old name readme_example.yaml).
marker_frame/: serialised motion_model_estimation/MarkerFrame messages (ROS wire format) for
               the 3-particle model of fuzz_marker_frame.cpp: valid, occluded, NaN, unknown
               names, mismatched lengths.
The regression_* inputs (one per bug found) are not generated: keep them.
Plain python3, no ROS import. Usage: test/fuzz/make_corpus.py
"""
import math
import os
import re
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
REAL = os.path.join(REPO, "test", "data", "real")
OUT = os.path.join(HERE, "corpus")


def put(target, name, data):
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(os.path.join(d, name), mode) as f:
        f.write(data)


def trc():
    # Few rows: small seeds keep the fuzzer fast; the header variants are what matters.
    for name, rows in [("arm26_elbow_flex.trc", 24), ("subject01_walk1.trc", 3),
                       ("motion_capture_walk.trc", 3)]:
        with open(os.path.join(REAL, name), "rb") as f:
            lines = f.read().split(b"\n")
        lines = lines[:6 + rows] + [b""]
        put("trc", name, b"\n".join(lines))


def trc_window(path, first, frames, markers):
    """A TRC file of `frames` rows from row `first` and the first `markers` markers."""
    lines = open(path, "rb").read().replace(b"\r", b"").split(b"\n")
    head, rows = lines[:5], [l for l in lines[5:] if l.strip()]
    meta = head[2].split()  # values, whatever the spacing (some writers pad with tabs)
    markers = min(markers, int(meta[3]))
    meta[2], meta[3] = str(frames).encode(), str(markers).encode()
    head[2] = b"\t".join(meta)
    names = head[3].split(b"\t")
    head[3] = b"\t".join(names[:2 + 3 * markers])
    head[4] = b"\t".join(head[4].split(b"\t")[:2 + 3 * markers])
    body = [b"\t".join(r.split(b"\t")[:2 + 3 * markers]) for r in rows[first:first + frames]]
    return b"\n".join(head + body) + b"\n"


def structure():
    captures = [os.path.join(REAL, n) for n in sorted(os.listdir(REAL)) if n.endswith(".trc")]
    captures.append(os.path.join(REPO, "test", "data", "crash", "window_0_99.trc"))
    for path in captures:
        rows = sum(1 for l in open(path, "rb").read().split(b"\n")[5:] if l.strip())
        for frames in (40, 80):
            if frames > rows:
                continue
            for first in sorted({0, rows - frames}):
                name = "%s_%d_%d.trc" % (os.path.basename(path)[:-4], first, frames)
                put("structure", name, trc_window(path, first, frames, 6))


def c3d():
    limit = 20 * 1024
    for name in sorted(os.listdir(REAL)):
        if not name.endswith(".c3d"):
            continue
        b = bytearray(open(os.path.join(REAL, name), "rb").read())
        proc = b[(b[0] - 1) * 512 + 3]
        e = ">" if proc == 86 else "<"
        word = lambda i: struct.unpack_from(e + "H", b, 2 * (i - 1))[0]
        points, analog, first, last, start = word(2), word(3), word(4), word(5), word(9)
        scale = struct.unpack_from(e + "f", b, 12)[0] if proc != 85 else -1.0
        size = 4 if scale < 0 else 2
        frame_bytes = (4 * points + analog) * size
        data_start = (start - 1) * 512
        frames = max(2, (limit - data_start) // frame_bytes)
        if frames < last - first + 1:
            struct.pack_into(e + "H", b, 8, first + frames - 1)
            cut = bytes(b[:data_start + frames * frame_bytes])
            put("c3d", name.replace(".c3d", "_cut.c3d"), cut)
        if len(b) < 100 * 1024:
            put("c3d", name, open(os.path.join(REAL, name), "rb").read())


def thin_model(text, keep):
    """Keeps the particles whose name satisfies keep(), and the bonds among them."""
    out, kept = [], set()
    for line in text.splitlines():
        m = re.match(r"\s*- \{name: ([^,]+), mass", line)
        if m:
            if not keep(m.group(1)):
                continue
            kept.add(m.group(1))
        m = re.match(r"\s*- \{type: [^,]+, particles: \[([^\]]+)\]\}", line)
        if m and not all(p.strip() in kept for p in m.group(1).split(",")):
            continue
        out.append(line)
    return "\n".join(out) + "\n"


def model_yaml():
    models = os.path.join(REPO, "config", "models")
    for name in sorted(os.listdir(models)):
        if not name.endswith(".yaml"):
            continue
        text = open(os.path.join(models, name)).read()
        if name.startswith("fluid"):
            text = thin_model(text, lambda p: int(p.split("_")[1]) < 4)
        elif name.startswith("provot"):
            text = thin_model(text, lambda p: all(int(k) < 3 for k in p.split("_")[1:]))
        elif name.startswith("walker"):
            text = thin_model(text, lambda p: p.startswith("leg_f") or p < "body_05")
        put("model_yaml", name, text)
    # docs/model_file.md's short example (p0, p1, spring type s01), extended.
    put("model_yaml", "readme_example.yaml", """frame_rate_hz: 100
gravity: {value: [0, 0, -9.81], free: [false, false, true], min: [~, ~, -20], max: 0}
particles:
  - {name: p0, mass: 1.0, position: [0, 0, 0], fixed: true}
  - {name: p1, mass: 0.5, position: [0, 0, -0.1], group: g}
  - {name: p2, mass: 0.5, position: [0.1, 0, -0.1], group: g}
bond_types:
  - name: s01
    kind: spring
    stiffness:   {value: 40.0, free: true, min: 1, max: 1000, std: 0.5}
    rest_length: {value: 0.08, free: true}
    damping: 0.1
    min_distance: 0.01
    max_elongation: 0.1
  - {name: f, kind: flexion, stiffness: 1, rest_angle: {value: 3.0, free: true}}
  - {name: v, kind: viscosity, viscosity: {value: 0.1, free: true}}
  - {name: near, kind: spring, stiffness: 2, rest_length: 0.1, max_distance: 0.2}
bonds:
  - {type: s01, particles: [p0, p1]}
  - {type: f, particles: [p0, p1, p2]}
  - {type: v, particles: [p2]}
interactions:
  - {type: near, groups: [g, g]}
identification: {method: es, global_cost: 1e-6, frames: 100, generations: 50}
""")


def marker_frame():
    def string(s):
        s = s.encode()
        return struct.pack("<I", len(s)) + s

    def frame(names, positions, occluded=(), sec=1000, nsec=0, frame_id="world", number=1):
        b = struct.pack("<III", 7, sec, nsec) + string(frame_id) + struct.pack("<I", number)
        b += struct.pack("<I", len(names)) + b"".join(string(n) for n in names)
        b += struct.pack("<I", len(positions)) + b"".join(struct.pack("<ddd", *p) for p in positions)
        b += struct.pack("<I", len(occluded)) + bytes(int(o) for o in occluded)
        return b

    p = [(0, 0, 0), (0, 0, -0.1), (0, 0.1, -0.1)]
    put("marker_frame", "valid", frame(["a", "b", "c"], p))
    put("marker_frame", "occluded", frame(["a", "b", "c"], p, [0, 1, 0]))
    put("marker_frame", "nan", frame(["a", "b", "c"], [p[0], (math.nan, 0, 0), (math.inf, 1, 2)]))
    put("marker_frame", "reordered_names", frame(["c", "a", "b"], p, sec=5, nsec=999999999))
    put("marker_frame", "unknown_names", frame(["a", "x", "c", "y"], p + [(1, 2, 3)]))
    put("marker_frame", "mismatched", frame(["a", "b"], p, [1]))
    put("marker_frame", "empty", frame([], []))
    put("marker_frame", "huge", frame(["a", "b", "c"], [(1e300, -1e300, 5e-324)] * 3,
                                      sec=4294967295, nsec=4294967295))


if __name__ == "__main__":
    trc()
    structure()
    c3d()
    model_yaml()
    marker_frame()
