#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Robustness probes of `citymesh run` on a small simulated street (session 60).

  tools/robustness/damage.py ply   BINARY [N] [SEED]   an acquisition's bytes damaged N ways
  tools/robustness/damage.py work  BINARY [N] [SEED]   a file of a finished work folder damaged
  tools/robustness/damage.py keys  BINARY              every config key at the ends of its range
  tools/robustness/damage.py append BINARY [N] [SEED]  a file of a finished work folder damaged,
                                                       then a pass over part of the street appended

Each case passes when the run either succeeds (for `work`: with the output bytes of the
undamaged run) or stops with an `error:` line and an exit code below 128, within the time
limit and without a sanitizer report (give an ASan build as BINARY to catch memory errors).
`append` (session 61) runs the first five passes on 10 m tiles, damages a file of that work
folder, then appends the sixth pass cut to the first fifth of the street (so that the tiles
waiting for the ones it reaches are looked at, and kept when nothing they read changed): the
run must give the bytes of a fresh run of the six passes, or a clean error.
`keys` also prints each run's time and peak RSS, and counts a run that takes more than 20
times the default's (plus 2 s) as bad: a value that is allowed must not make a run crawl. Prints one line per case and the count of bad ones; exits 1
when there are any. Works in a temporary folder.
"""
import hashlib
import os
import random
import re
import shutil
import struct
import subprocess
import sys
import tempfile

ENV = dict(os.environ, ASAN_OPTIONS="detect_leaks=1", UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")


def run(binary, folder, extra=(), timeout=600, config="config.toml"):
    """(exit code or 'TIMEOUT', stderr) of `citymesh run config.toml` in `folder`."""
    try:
        p = subprocess.run(["/usr/bin/time", "-f", "time %e s, peak RSS %M kB", binary, "run", config,
                            "--no-pictures", "--set", "output.ply=true", *extra],
                           cwd=folder, capture_output=True, timeout=timeout, env=ENV)
        return p.returncode, p.stderr.decode(errors="replace")
    except subprocess.TimeoutExpired:
        return "TIMEOUT", ""


def verdict(rc, err, same=True):
    """Whether a run ended well: success (with the expected output) or a clean error."""
    if "Sanitizer" in err or "runtime error" in err or rc == "TIMEOUT":
        return False
    return (rc == 0 and same) or (0 < rc < 128 and "error" in err)


def first_error(err):
    lines = [line for line in err.splitlines() if line.startswith("error") or "Sanitizer" in line]
    return lines[0][:200] if lines else ""


def seconds(err):
    """The wall time /usr/bin/time wrote last on stderr (0 when it is not there)."""
    found = re.findall(r"time ([0-9.]+) s, peak RSS", err)
    return float(found[-1]) if found else 0.0


def output_digest(folder):
    h = hashlib.sha256()
    for root, _, files in sorted(os.walk(os.path.join(folder, "out"))):
        for name in sorted(files):
            if name in ("run.json", "summary.json"):
                continue  # timings
            h.update(name.encode())
            with open(os.path.join(root, name), "rb") as f:
                h.update(f.read())
    return h.hexdigest()


def damaged_ply(data, rnd):
    """The bytes of a binary PLY damaged one of several ways: bytes flipped, an index, a
    coordinate or a list count changed, cut short, a header count or type changed."""
    end = data.index(b"end_header\n") + len(b"end_header\n")
    d = bytearray(data)
    kind = rnd.randrange(5)
    if kind == 0:
        for _ in range(rnd.randint(1, 8)):
            d[rnd.randrange(end, len(d))] = rnd.randrange(256)
    elif kind == 1:
        at = rnd.randrange(end, len(d) - 8)
        d[at:at + 8] = struct.pack("<d", rnd.choice([float("nan"), float("inf"), 1e300, -1e12]))
    elif kind == 2:
        at = rnd.randrange(end, len(d) - 4)
        d[at:at + 4] = struct.pack("<I", rnd.choice([0xFFFFFFFF, 2**31, rnd.randrange(2**32)]))
    elif kind == 3:
        d = d[:rnd.randrange(len(d))]
    else:
        header = data[:end].decode()
        header = re.sub(r"element (vertex|face) \d+",
                        lambda m: f"element {m.group(1)} {rnd.choice([0, 1, 10**9, 2**32, -1])}", header, count=1)
        header = header.replace("list uchar", rnd.choice(["list uint", "list char", "list uchar"]))
        d = bytearray(header.encode()) + data[end:]
    return bytes(d)


def damaged_file(data, rnd):
    """Bits flipped, cut short or emptied."""
    d = bytearray(data)
    kind = rnd.randrange(3)
    if kind == 0 and d:
        for _ in range(rnd.randint(1, 4)):
            d[rnd.randrange(len(d))] ^= 1 << rnd.randrange(8)
    elif kind == 1:
        d = d[:rnd.randrange(len(d) + 1)]
    else:
        d = bytearray()
    return bytes(d)


def first_part(data, share):
    """A binary little-endian PLY as `citymesh simulate` writes it (seven doubles per vertex, faces
    as a uchar count and uint indices) with only the faces whose centroid lies in the first
    `share` of its x extent."""
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    vertices = int(re.search(r"element vertex (\d+)", header).group(1))
    faces = int(re.search(r"element face (\d+)", header).group(1))
    xs = [struct.unpack_from("<d", data, end + 56 * v)[0] for v in range(vertices)]
    cut = min(xs) + share * (max(xs) - min(xs))
    kept, at = [], end + 56 * vertices
    for _ in range(faces):
        n = data[at]
        ids = struct.unpack_from(f"<{n}I", data, at + 1)
        if sum(xs[i] for i in ids) / n < cut:
            kept.append(data[at:at + 1 + 4 * n])
        at += 1 + 4 * n
    header = re.sub(r"element face \d+", f"element face {len(kept)}", header)
    return header.encode() + data[end:end + 56 * vertices] + b"".join(kept)


def append_configs(folder):
    """five.toml (the config less its last acquisition) and six.toml (with the last one cut
    to the first fifth of the street), in `folder`."""
    with open(os.path.join(folder, "config.toml")) as f:
        config = f.read()
    last = config.rindex("[[acquisition]]")
    sixth = config[last:]
    path = re.search(r'path = "(.*)"', sixth).group(1)
    with open(os.path.join(folder, path), "rb") as f:
        part = first_part(f.read(), 0.2)
    with open(os.path.join(folder, "part.ply"), "wb") as f:
        f.write(part)
    with open(os.path.join(folder, "five.toml"), "w") as f:
        f.write(config[:last])
    with open(os.path.join(folder, "six.toml"), "w") as f:
        f.write(config[:last] + sixth.replace(path, "part.ply"))


APPEND_TILES = ("--set", "tiling.tile_size=10")

KEY_ENDS = {
    "change.distance_threshold": ["0.001", "10"], "change.conflict_margin": ["0", "10"],
    "change.normal_angle": ["0", "90"], "change.voxel_size": ["0.05", "10"],
    "mosaic.quality_weight": ["0", "1000000"], "mosaic.boundary_weight": ["0", "1000000"],
    "mosaic.overlap_weight": ["0", "1000000000"], "mosaic.seam_weight": ["0", "1000000"],
    "mosaic.crease_weight": ["0", "1000000"], "mosaic.sweeps": ["1", "100"],
    "mosaic.later_sweep_reach": ["0", "100000"], "mosaic.stitch_reach": ["0.1", "100"],
    "mosaic.clip_reach": ["0.1", "10"], "mosaic.gap_width": ["0.1", "10"],
    "tiling.tile_size": ["1", "100000"], "tiling.halo": ["0", "0.49"], "run.threads": ["1", "1024"],
    "output.draco_tolerance": ["1e-05", "1"], "run.memory": ['"64MiB"', '"100TiB"'],
    "tiling.origin": ["[1e9, -1e9]"], "change.sustainability": ['"0s"', '"100000d"'],
}


def main():
    if len(sys.argv) < 3 or sys.argv[1] not in ("ply", "work", "keys", "append"):
        print(__doc__, file=sys.stderr)
        return 2
    mode, binary = sys.argv[1], os.path.abspath(sys.argv[2])
    n = int(sys.argv[3]) if len(sys.argv) > 3 else 100
    rnd = random.Random(int(sys.argv[4]) if len(sys.argv) > 4 else 1)
    bad = 0
    with tempfile.TemporaryDirectory() as tmp:
        street = os.path.join(tmp, "street")
        subprocess.run([binary, "simulate", "--out", street, "--length", "30", "--line-rate", "5",
                        "--angular-step", "5"], check=True, capture_output=True)
        reference = os.path.join(tmp, "reference")
        shutil.copytree(street, reference)
        if mode == "append":
            append_configs(reference)
            fresh = os.path.join(tmp, "fresh")
            shutil.copytree(reference, fresh)
            rc, err = run(binary, fresh, APPEND_TILES, config="six.toml")
            assert rc == 0, err
            good = output_digest(fresh)
            rc, err = run(binary, reference, APPEND_TILES, config="five.toml")
        else:
            rc, err = run(binary, reference)
            good = output_digest(reference)
        assert rc == 0, err
        slow = 20 * seconds(err) + 2
        work_files = [os.path.join(r, f) for r, _, fs in os.walk(os.path.join(reference, "work")) for f in fs]
        cases = ([(k, v) for k, vs in KEY_ENDS.items() for v in vs] if mode == "keys" else range(n))
        for i, case in enumerate(cases):
            folder = os.path.join(tmp, f"case{i}")
            shutil.copytree(reference if mode in ("work", "append") else street, folder)
            shutil.rmtree(os.path.join(folder, "out"), ignore_errors=True)
            extra, what = (), ""
            if mode == "ply":
                path = os.path.join(folder, "acq_2.ply")
                with open(path, "rb") as f:
                    data = f.read()
                with open(path, "wb") as f:
                    f.write(damaged_ply(data, rnd))
            elif mode in ("work", "append"):
                path = rnd.choice(work_files).replace(reference, folder)
                what = os.path.relpath(path, folder)
                with open(path, "rb") as f:
                    data = f.read()
                with open(path, "wb") as f:
                    f.write(damaged_file(data, rnd))
            else:
                extra, what = ("--set", f"{case[0]}={case[1]}"), f"{case[0]}={case[1]}"
            if mode == "append":
                rc, err = run(binary, folder, APPEND_TILES, config="six.toml")
            else:
                rc, err = run(binary, folder, extra)
            same = mode not in ("work", "append") or (rc == 0 and output_digest(folder) == good)
            ok = verdict(rc, err, same) and (mode != "keys" or seconds(err) < slow)
            bad += 0 if ok else 1
            resources = err.strip().splitlines()[-1] if err.strip() else ""
            print("ok " if ok else "BAD", i, what, rc, first_error(err) or resources, flush=True)
            shutil.rmtree(folder)
    print(f"{bad} bad of {len(cases)}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
