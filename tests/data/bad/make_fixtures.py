#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# Writes the malformed PLY and config files of this folder and cases.tsv, which says for each
# file which command reads it, and the error class, exit code and message fragment expected.
# Re-run after changing a case: python3 tests/data/bad/make_fixtures.py
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
cases = []


def ply(name, data, command, kind, code, fragment):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())
    cases.append((name, command, kind, code, fragment))


def ascii_header(vertex_props="x y z x_origin y_origin z_origin", nv=3, faces=None, extra=""):
    h = "ply\nformat ascii 1.0\n" + extra + f"element vertex {nv}\n"
    h += "".join(f"property float {p}\n" for p in vertex_props.split())
    if faces is not None:
        h += f"element face {faces}\nproperty list uchar int vertex_indices\n"
    return h + "end_header\n"


V3 = "0 0 0 0 0 2\n1 0 0 1 0 2\n0 1 0 0 1 2\n"
INPUT = ("input", 2)

# ---- PLY header -----------------------------------------------------------------------------
ply("empty.ply", "", "info", *INPUT, "not a PLY file")
ply("wrong_magic.ply", "plx\nformat ascii 1.0\nend_header\n", "info", *INPUT, "not a PLY file")
ply("no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "info", *INPUT,
    "no 'end_header'")
ply("bad_format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", "info", *INPUT, "unknown format")
ply("bad_version.ply", "ply\nformat ascii 2.0\nend_header\n", "info", *INPUT, "unsupported PLY version")
ply("unknown_type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty int128 x\nend_header\n1\n", "info",
    *INPUT, "unknown property type 'int128'")
ply("property_before_element.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n", "info", *INPUT,
    "property before any element")
ply("negative_count.ply", "ply\nformat ascii 1.0\nelement vertex -5\nproperty float x\nend_header\n", "info",
    *INPUT, "not a non-negative integer")
ply("duplicate_element.ply",
    "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nelement vertex 0\nend_header\n", "info", *INPUT,
    "declared twice")
ply("duplicate_property.ply",
    "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float x\nend_header\n", "info", *INPUT,
    "declared twice")
ply("element_without_properties.ply", "ply\nformat ascii 1.0\nelement vertex 1000000\nend_header\n", "info",
    *INPUT, "no properties")
ply("float_list_count.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
    "property float z\nelement face 0\nproperty list float int vertex_indices\nend_header\n", "info", *INPUT,
    "count type must be an integer")
ply("bad_offset_comment.ply", ascii_header(extra="comment offset Pos 649000 6840000\n") + V3, "info", *INPUT,
    "offset comment")
ply("unknown_keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 1\nend_header\n", "info", *INPUT,
    "unknown header keyword 'elemnt'")

# ---- counts against the file size -----------------------------------------------------------
binary_vertex = "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\n" \
                "property double z\nend_header\n"
ply("huge_count.ply", binary_vertex.format(10**12).encode() + struct.pack("<3d", 0, 0, 0), "info", *INPUT,
    "need at least 24000000000000 bytes")
ply("truncated_binary.ply", binary_vertex.format(10).encode() + struct.pack("<15d", *range(15)), "info", *INPUT,
    "truncated file or wrong counts")
faces_hdr = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n")
ply("truncated_faces.ply", faces_hdr.encode() + struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    + struct.pack("<B3i", 3, 0, 1, 2) + struct.pack("<B", 3), "info", *INPUT, "face 1: unexpected end of file")
ply("truncated_ascii.ply", ascii_header(nv=4) + V3.replace("0 ", "0.000000 ").replace("1 ", "1.000000 "), "info",
    *INPUT, "vertex 3: unexpected end of file")
long_list = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n")
ply("list_too_long.ply", long_list.encode() + struct.pack("<9f", *[0.0] * 9) + struct.pack("<I", 100000)
    + b"\0" * 64, "info", *INPUT, "list length 100000 is out of range")

# ---- element structure ----------------------------------------------------------------------
ply("no_vertex_element.ply", "ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n1\n", "info",
    *INPUT, "no 'vertex' element")
ply("missing_z.ply", ascii_header("x y", nv=1) + "0 0\n", "info", *INPUT, "lacks one of the properties x, y, z")
ply("no_vertex_indices.ply", ascii_header(nv=3).replace(
    "end_header", "element face 1\nproperty list uchar int verts\nend_header") + V3 + "3 0 1 2\n", "info", *INPUT,
    "no 'vertex_indices'")
ply("float_indices.ply", ascii_header(nv=3).replace(
    "end_header", "element face 1\nproperty list uchar float vertex_indices\nend_header") + V3 + "3 0 1 2\n", "info",
    *INPUT, "must hold integers")
ply("scalar_vertex_indices.ply", ascii_header(nv=3).replace(
    "end_header", "element face 1\nproperty int vertex_indices\nend_header") + V3 + "0\n", "info", *INPUT,
    "must be a list")
ply("missing_sensor_origin.ply", ascii_header("x y z", nv=1) + "0 0 0\n", "info-origin", *INPUT,
    "no sensor position")
ply("partial_sensor_origin.ply", ascii_header("x y z x_origin y_origin", nv=1) + "0 0 0 0 0\n", "info", *INPUT,
    "no sensor position")

# ---- rows -----------------------------------------------------------------------------------
ply("face_index_out_of_range.ply", ascii_header(faces=1) + V3 + "3 0 1 7\n", "info", *INPUT,
    "face 0: vertex index 7 is out of range")
neg = faces_hdr.replace("element face 2", "element face 1").encode()
ply("negative_face_index.ply", neg + struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, -1, 2),
    "info", *INPUT, "vertex index -1 is out of range")
ply("nan_coordinate.ply", ascii_header() + "0 0 0 0 0 2\nnan 0 0 1 0 2\n0 1 0 0 1 2\n", "info", *INPUT,
    "vertex 1: position is not finite")
inf_hdr = ("ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
           "property float z\nend_header\n")
ply("inf_coordinate_big_endian.ply", inf_hdr.encode() + struct.pack(">6f", 0, 0, 0, 1, float("inf"), 0), "info",
    *INPUT, "vertex 1: position is not finite")
ply("nan_sensor_origin.ply", ascii_header() + "0 0 0 0 0 2\n1 0 0 1 nan 2\n0 1 0 0 1 2\n", "info", *INPUT,
    "vertex 1: sensor position is not finite")
ply("sensor_too_far.ply", ascii_header() + "0 0 0 0 0 2\n1 0 0 1 0 2002\n0 1 0 0 1 2\n", "info", *INPUT,
    "vertex 1: lies 2002 m from its sensor position")
ply("zero_length_list.ply", ascii_header(faces=2) + V3 + "3 0 1 2\n0\n", "info", *INPUT, "face 1: empty vertex list")
ply("bad_ascii_value.ply", ascii_header() + "0 0 0 0 0 2\n1 abc 0 1 0 2\n0 1 0 0 1 2\n", "info", *INPUT,
    "'abc' is not a number")
ply("extra_ascii_value.ply", ascii_header() + "0 0 0 0 0 2 9\n1 0 0 1 0 2\n0 1 0 0 1 2\n", "info", *INPUT,
    "unexpected extra value '9'")
ply("missing_face_index.ply", ascii_header(faces=1) + V3 + "3 0 1\n", "info", *INPUT, "fewer vertex indices")

# ---- configs --------------------------------------------------------------------------------
GOOD_PLY = "good_tiny.ply"
with open(os.path.join(HERE, GOOD_PLY), "w") as f:
    f.write(ascii_header(faces=1) + V3 + "3 0 1 2\n")

BASE = {
    "project": 'crs = "EPSG:2154"\nvertical_datum = "ellipsoidal"\n',
    "acq": f'[[acquisition]]\npath = "{GOOD_PLY}"\ntime = "2026-01-05T10:00:00Z"\n',
}
CONFIG = ("config", 1)


def toml(name, text, fragment, kind="config"):
    ply(name, text, "check", kind, 1, fragment)


def cfg(project=BASE["project"], acq=BASE["acq"], extra=""):
    return f"[project]\n{project}\n{extra}\n{acq}"


toml("syntax_error.toml", "[project\ncrs = 1\n", "syntax_error.toml:1:")
toml("unknown_key.toml", cfg(extra="[change]\ndistance_treshold = 0.1\n"),
     "did you mean 'change.distance_threshold'?")
toml("unknown_section.toml", cfg(extra="[chnage]\ndistance_threshold = 0.1\n"), "did you mean 'change'?")
toml("missing_crs.toml", cfg(project='vertical_datum = "ellipsoidal"\n'), "project.crs is required")
toml("unsupported_crs.toml", cfg(project='crs = "EPSG:4326"\nvertical_datum = "ellipsoidal"\n'),
     "EPSG:4326 is not supported")
toml("bad_enu.toml", cfg(project='crs = "ENU:48.8,2.3"\nvertical_datum = "ellipsoidal"\n'),
     "ENU needs three numbers")
toml("missing_vertical_datum.toml", cfg(project='crs = "EPSG:2154"\n'), "project.vertical_datum is required")
toml("bad_vertical_datum.toml", cfg(project='crs = "EPSG:2154"\nvertical_datum = "geoid"\n'),
     "expected \"ellipsoidal\" or \"orthometric\"")
toml("undulation_with_ellipsoidal.toml", cfg(project=BASE["project"] + "geoid_undulation = 44.5\n"),
     "only meaningful")
toml("wrong_type.toml", cfg(extra='[change]\ndistance_threshold = "ten"\n'), "expected a number from 0.001 to 10")
toml("out_of_range.toml", cfg(extra="[change]\ndistance_threshold = -1\n"), "change.distance_threshold: expected")
toml("bad_duration.toml", cfg(extra='[change]\nsustainability = "30 days"\n'), "expected a duration")
toml("bad_size.toml", cfg(extra='[run]\nmemory = "2 gigs"\n'), "expected a size")
toml("small_memory.toml", cfg(extra='[run]\nmemory = "1MiB"\n'), "at least 64MiB")
toml("fractional_threads.toml", cfg(extra="[run]\nthreads = 1.5\n"), "expected a whole number")
toml("bad_quality.toml", cfg(extra='[mosaic]\nquality = "best"\n'), "expected one of \"constant\", \"area\"")
toml("sensor_origin_two_names.toml", cfg(extra='[input]\nsensor_origin = ["ox", "oy"]\n'),
     "expected an array of 3 strings")
toml("halo_too_big.toml", cfg(extra="[tiling]\ntile_size = 10\nhalo = 6\n"), "less than half")
toml("bad_date.toml", cfg(acq=f'[[acquisition]]\npath = "{GOOD_PLY}"\ntime = "2026-13-05"\n'),
     "no such calendar date")
toml("time_without_zone.toml", cfg(acq=f'[[acquisition]]\npath = "{GOOD_PLY}"\ntime = "2026-01-05T10:00:00"\n'),
     "needs a time zone")
toml("missing_time.toml", cfg(acq=f'[[acquisition]]\npath = "{GOOD_PLY}"\n'), "missing 'time'")
toml("missing_path.toml", cfg(acq='[[acquisition]]\ntime = "2026-01-05"\n'), "missing 'path'")
toml("missing_file.toml", cfg(acq='[[acquisition]]\npath = "nowhere.ply"\ntime = "2026-01-05"\n'),
     "no such file")
toml("no_acquisitions.toml", cfg(acq=""), "no [[acquisition]] tables")
toml("acquisition_not_array.toml", cfg(acq=f'[acquisition]\npath = "{GOOD_PLY}"\ntime = "2026-01-05"\n'),
     "[[acquisition]] table")
toml("unknown_acquisition_key.toml", cfg(acq=f'[[acquisition]]\npth = "{GOOD_PLY}"\ntime = "2026-01-05"\n'),
     "did you mean 'path'?")
toml("same_file_twice.toml", cfg(acq=BASE["acq"] + BASE["acq"].replace("2026-01-05", "2026-02-05")),
     "name the same file")
toml("section_not_table.toml", "change = 3\n" + cfg(), "expected a [section] table")

with open(os.path.join(HERE, "cases.tsv"), "w") as f:
    f.write("# file\tcommand\tkind\texit_code\tmessage fragment\n")
    for c in cases:
        f.write("\t".join(str(x) for x in c) + "\n")
print(f"{len(cases)} cases written")
