#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets, tests/fuzz/corpus/<target>/.

A few valid inputs per target, in the input formats each target's header comment
describes, so that fuzzing starts from messages, sessions and plans that get past the
first checks. The outputs are committed; run this again only when a format changes:

    PYTHONPATH=build/proto/python /usr/bin/python3 tests/fuzz/make_corpus.py

(needs python3-protobuf and the modules the build generates from floorpose.proto).
"""

import json
import math
import pathlib
import shutil
import struct
import zlib

from floorpose.v1 import floorpose_pb2 as pb

OUT = pathlib.Path(__file__).resolve().parent / "corpus"

# The room of mesh_ingest_fuzzer.cc: 6 x 4 m and a stub, plan x/y = Unity x/z.
WALLS = [((0, 0), (6, 0)), ((6, 0), (6, 4)), ((6, 4), (0, 4)), ((0, 4), (0, 0)),
         ((2, 0), (2, 1.5))]


def write(target, name, data):
    d = OUT / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data)


def quad(a, b, height=2.8):
    """A wall face from plan points a to b, Unity frame (y up): vertices, triangles."""
    vertices = [(a[0], 0, a[1]), (b[0], 0, b[1]), (b[0], height, b[1]), (a[0], height, a[1])]
    return vertices, [0, 1, 2, 0, 2, 3]


# --- codec_fuzzer: selector byte (kind, frame, tight limits), then the payload ----------


def codec():
    vertices, triangles = quad(*WALLS[1])
    mesh = pb.MeshDelta(mesh_id=7, change=pb.MeshDelta.ADDED, stamp_ns=1_000_000_000,
                        vertices=[c for v in vertices for c in v], triangles=triangles)
    write("codec_fuzzer", "mesh_added", b"\x00" + mesh.SerializeToString())
    write("codec_fuzzer", "mesh_added_zup_tight", b"\x0c" + mesh.SerializeToString())
    moved = pb.MeshDelta()
    moved.CopyFrom(mesh)
    moved.change = pb.MeshDelta.UPDATED
    moved.mesh_to_world.extend([1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, -0.25, 0, 0, 0, 1])
    write("codec_fuzzer", "mesh_updated_transform", b"\x00" + moved.SerializeToString())
    removed = pb.MeshDelta(mesh_id=7, change=pb.MeshDelta.REMOVED, stamp_ns=2_000_000_000)
    write("codec_fuzzer", "mesh_removed", b"\x00" + removed.SerializeToString())

    yaw = math.radians(30)
    pose = pb.HeadsetPose(stamp_ns=1_300_000_000, tracking=pb.HeadsetPose.TRACKING_OK,
                          position=pb.Vec3(x=3, y=1.6, z=2),
                          orientation=pb.Quaternion(y=math.sin(yaw / 2), w=math.cos(yaw / 2)))
    write("codec_fuzzer", "pose", b"\x01" + pose.SerializeToString())
    pose.tracking = pb.HeadsetPose.TRACKING_LOST
    write("codec_fuzzer", "pose_lost_zup", b"\x05" + pose.SerializeToString())

    commands = {
        "load_plan": pb.Command(request_id=1, load_plan=pb.Command.LoadPlan(plan_id="room",
                                                                           floor="2")),
        "wall_pick": pb.Command(request_id=2, wall_pick=pb.Command.WallPick(
            headset_point=pb.Vec3(x=6, y=1.5, z=2), headset_normal=pb.Vec3(x=-1),
            plan_x=6, plan_y=2, plan_normal_x=-1)),
        "flip": pb.Command(request_id=3, flip=pb.Command.Flip()),
        "reset": pb.Command(request_id=4, reset=pb.Command.Reset()),
        "get_state": pb.Command(request_id=5, get_state=pb.Command.GetState()),
    }
    for name, command in commands.items():
        write("codec_fuzzer", "command_" + name, b"\x02" + command.SerializeToString())

    record = pb.RecordingRecord(receive_stamp_ns=5, topic="floorpose/v1/mesh_delta",
                                envelope=pb.Envelope(device_id="hololens-1", seq=1,
                                                     stamp_ns=4, payload=mesh.SerializeToString()))
    write("codec_fuzzer", "record_mesh", b"\x03" + record.SerializeToString())
    record.topic = "floorpose/v1/headset_pose"
    record.envelope.payload = pose.SerializeToString()
    write("codec_fuzzer", "record_pose", b"\x03" + record.SerializeToString())


# --- mesh_ingest_fuzzer: operations (see the target's header comment) -------------------


def cm(v):
    return struct.pack("<h", round(v * 100))


def turn(angle):
    """An angle as the target's byte: 1/256 of a turn."""
    return bytes([round(angle / (2 * math.pi) * 256) % 256])


def op_mesh(mesh_id, change, vertices, triangles, step=10, raw=False, transform=None):
    header = change | (4 if raw else 0) | (8 if transform else 0) | (mesh_id << 4)
    out = bytes([0, header, len(vertices), len(triangles) // 3])
    if transform:
        out += struct.pack("<16f", *transform)
    for v in vertices:
        out += struct.pack("<3f", *v) if raw else b"".join(cm(c) for c in v)
    return out + bytes(triangles) + bytes([step])


def op_pose(x, z, yaw, tracking=1, step=30, height=1.6):
    return bytes([1]) + cm(x) + cm(height) + cm(z) + turn(yaw) + bytes([tracking, step])


def op_wall_pick(point, normal_yaw, plan_point, plan_heading):
    return (bytes([2, 0]) + cm(point[0]) + cm(point[1]) + cm(point[2]) + turn(normal_yaw) +
            cm(plan_point[0]) + cm(plan_point[1]) + turn(plan_heading))


def walls(first_id=1, step=10):
    out = b""
    for i, (a, b) in enumerate(WALLS):
        out += op_mesh(first_id + i, pb.MeshDelta.ADDED, *quad(a, b), step=step)
    return out


def walk(poses=20):
    # Round the room at 1.2 m from the walls, a pose every 0.3 s.
    out = b""
    for i in range(poses):
        a = 2 * math.pi * i / poses
        out += op_pose(3 + 1.8 * math.cos(a), 2 + 0.8 * math.sin(a), a + math.pi / 2)
    return out


def mesh_ingest():
    # Unity normal (sin, 0, cos) of the east wall faces west: yaw 270 degrees.
    pick = op_wall_pick((6, 1.5, 2), math.radians(270), (6, 2), math.pi)
    write("mesh_ingest_fuzzer", "session",
          op_pose(3, 2, 0) + pick + walls() + walk() + walls(step=100) + walk())
    # The same session seen a little rotated (SLAM drift): registration corrects it.
    drifted = [((a[0] + 0.1 * a[1], a[1] - 0.1 * a[0]), (b[0] + 0.1 * b[1], b[1] - 0.1 * b[0]))
               for a, b in WALLS]
    out = op_pose(3, 2, 0) + pick
    for i, (a, b) in enumerate(drifted):
        out += op_mesh(i + 1, pb.MeshDelta.ADDED, *quad(a, b), step=100)
    write("mesh_ingest_fuzzer", "drifted", out + walk(30))
    # Updates, removals, unknown ids, a transform, raw floats with a NaN and bad indices.
    vertices, triangles = quad(*WALLS[0])
    odd = (op_mesh(1, pb.MeshDelta.ADDED, vertices, triangles) +
           op_mesh(1, pb.MeshDelta.UPDATED, vertices, triangles,
                   transform=[1, 0, 0, 0.2, 0, 1, 0, 0, 0, 0, 1, 0.1, 0, 0, 0, 1]) +
           op_mesh(2, pb.MeshDelta.UPDATED, vertices, triangles) +
           op_mesh(1, pb.MeshDelta.REMOVED, [], []) + op_mesh(9, pb.MeshDelta.REMOVED, [], []) +
           op_mesh(3, pb.MeshDelta.ADDED, vertices + [(math.nan, 0, 0)], triangles + [0, 4, 9],
                   raw=True) + op_pose(1, 1, 0, tracking=3))
    write("mesh_ingest_fuzzer", "odd_meshes", odd)
    # Every command, then raw payloads: a pose, junk, another device's mesh, a stamp jump.
    pose = pb.HeadsetPose(stamp_ns=5, position=pb.Vec3(x=1, y=1.6, z=1),
                          orientation=pb.Quaternion(w=1)).SerializeToString()
    commands = (bytes([2, 4, 1]) + pick + walls() + bytes([2, 1, 2, 3, 2, 5, 2, 4, 0]) +
                walk(5) + bytes([2, 2]))
    raw = (bytes([3, 1]) + struct.pack("<H", len(pose)) + pose + bytes([3, 0, 3, 0, 1, 2, 3]) +
           bytes([3, 3]) + struct.pack("<H", 2) + b"\x08\x01" +
           op_pose(2, 2, 0, step=255) + struct.pack("<q", -(2**63)) + op_pose(2, 2, 0))
    write("mesh_ingest_fuzzer", "commands_raw", commands + raw)


# --- plan_loader_fuzzer: format byte (0 GeoJSON, 1 text, 2 raster), then the files -------


def png(width, height, pixels):
    """An 8-bit grey PNG; pixels row by row from the top."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data)))
    rows = b"".join(b"\x00" + bytes(pixels[y * width:(y + 1) * width]) for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0,
                                                               0, 0)) +
            chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))


def plan_loader():
    lines = [{"type": "Feature", "properties": {"kind": "wall"},
              "geometry": {"type": "LineString", "coordinates": [list(a), list(b)]}}
             for a, b in WALLS]
    lines.append({"type": "Feature", "properties": {"kind": "door"},
                  "geometry": {"type": "LineString", "coordinates": [[1, 0], [1.9, 0]]}})
    geojson = {"type": "FeatureCollection", "features": lines}
    write("plan_loader_fuzzer", "lines.geojson", b"\x00" + json.dumps(geojson).encode())
    shapes = {"type": "GeometryCollection", "geometries": [
        {"type": "Polygon", "coordinates": [[[0, 0], [6, 0], [6, 4], [0, 4], [0, 0]]]},
        {"type": "MultiPolygon", "coordinates": [[[[1, 1], [2, 1], [2, 2], [1, 1]]]]},
        {"type": "MultiLineString", "coordinates": [[[3, 0], [3, 1.5]], [[4, 4], [4, 3]]]},
        {"type": "Point", "coordinates": [1, 1]}]}
    write("plan_loader_fuzzer", "shapes.geojson", b"\x00" + json.dumps(shapes).encode())
    text = f"{len(WALLS)}\n" + "".join(f"{a[0]} {a[1]} {b[0]} {b[1]}\n" for a, b in WALLS)
    write("plan_loader_fuzzer", "room.txt", b"\x01" + text.encode())
    # A 6 x 4 m room at 0.25 m a pixel, walls black, free space white.
    w, h = 24, 16
    pixels = [0 if x in (0, w - 1) or y in (0, h - 1) or (x == 8 and y > 9) else 255
              for y in range(h) for x in range(w)]
    for name, yaml in {
        "raster": "image: plan.png\nresolution: 0.25\norigin: [0.0, 0.0, 0.0]\n"
                  "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
        "raster_negate": "image: plan.png\nresolution: 0.05\norigin: [-1, 2]\nnegate: 1\n",
    }.items():
        data = yaml.encode()
        image = png(w, h, [255 - p for p in pixels] if "negate" in name else pixels)
        write("plan_loader_fuzzer", name, b"\x02" + struct.pack("<H", len(data)) + data + image)


def snapshot():
    """A restored state: an alignment with its filter and two meshes of wall points, as a
    payload (odd first byte) and as a whole file with its header and CRC (even)."""
    s = pb.StateSnapshot(device_id="fuzz-headset", plan_path="room.geojson", floor="0",
                         latest_stamp_ns=30_000_000_000, next_version=4, drift_scale=1.0,
                         pivot_x=3.0, pivot_y=2.0, has_pick=True, pick_x=0.0, pick_y=2.0,
                         start_pivot_x=0.0, start_pivot_y=2.0, fused=2)
    a = s.alignment
    a.t_plan_slam.theta, a.t_plan_slam.x, a.t_plan_slam.y = 0.1, 0.5, -0.2
    a.version, a.source, a.floor, a.stamp_ns = 3, pb.Alignment.REGISTRATION, "0", 29_000_000_000
    s.covariance.extend([0.001, 0, 0, 0, 0.04, 0, 0, 0, 0.04])
    for mesh_id, (p, q) in enumerate([((0.1, 0.0), (5.9, 0.0)), ((6.0, 0.1), (6.0, 3.9))], 1):
        m = s.meshes.add(mesh_id=mesh_id, stamp_ns=mesh_id * 1_000_000_000)
        for k in range(12):
            t = k / 11
            m.points.extend([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])])
            m.normals.extend([0.0, 1.0] if p[1] == q[1] else [-1.0, 0.0])
    payload = s.SerializeToString()
    write("snapshot_fuzzer", "payload", b"\x01" + payload)
    header = b"FPSNAP1\n" + struct.pack("<QI", len(payload), zlib.crc32(payload))
    write("snapshot_fuzzer", "file", b"\x00" + header + payload)
    s.alignment.version, s.next_version = 0, 1
    s.ClearField("covariance")
    write("snapshot_fuzzer", "walls_only", b"\x01" + s.SerializeToString())


if __name__ == "__main__":
    shutil.rmtree(OUT, ignore_errors=True)
    codec()
    mesh_ingest()
    plan_loader()
    snapshot()
    sizes = sorted((p.stat().st_size, str(p.relative_to(OUT))) for p in OUT.rglob("*")
                   if p.is_file())
    print(f"{len(sizes)} seeds, {sum(s for s, _ in sizes)} bytes in {OUT}")
