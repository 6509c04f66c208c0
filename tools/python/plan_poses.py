#!/usr/bin/env python3
"""Print the plan poses of a floorpose recording: an example client in Python.

A recording (docs/protocol.md, section 8) is what `floorpose record` wrote of a live
session, or what `floorpose eval --session` computed from a simulated walk. This reads it
with nothing but the protobuf runtime (Debian: python3-protobuf) and the modules protoc
generates from proto/floorpose/v1/floorpose.proto:

    protoc --python_out=OUT -I proto proto/floorpose/v1/floorpose.proto
    PYTHONPATH=OUT python3 tools/python/plan_poses.py session.rec

(the build does the first step into build/proto/python). One line per plan pose:

    stamp_s  x  y  heading  floor  alignment_version  flag  probability  reason
"""

import argparse
import math
import sys

try:
    from google.protobuf.internal.decoder import _DecodeVarint32
    from google.protobuf.message import DecodeError
    from floorpose.v1 import floorpose_pb2
except ImportError as e:
    sys.exit(f"plan_poses.py: {e}: install python3-protobuf and put the modules generated "
             "from proto/floorpose/v1/floorpose.proto on PYTHONPATH (see --help)")

MAGIC = b"FPREC01\n"
PLAN_POSE_TOPIC = "floorpose/v1/plan_pose"


def records(path):
    """Yields the RecordingRecords of a recording file; raises ValueError when corrupt."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:len(MAGIC)] != MAGIC:
        raise ValueError(f"{path}: not a floorpose recording (no {MAGIC!r} magic)")
    pos = len(MAGIC)
    while pos < len(data):
        size, pos = _DecodeVarint32(data, pos)
        if pos + size > len(data):
            raise ValueError(f"{path}: record at byte {pos} runs past the end of the file")
        yield floorpose_pb2.RecordingRecord.FromString(data[pos:pos + size])
        pos += size


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("recording")
    parser.add_argument("--device", help="only this device id (default: every device)")
    args = parser.parse_args()

    flag_name = floorpose_pb2.Reliability.Flag.Name
    count = reliable = 0
    print("# stamp_s x y heading floor alignment_version flag probability reason")
    try:
        for rec in records(args.recording):
            if rec.topic != PLAN_POSE_TOPIC:
                continue
            if args.device and rec.envelope.device_id != args.device:
                continue
            p = floorpose_pb2.PlanPose.FromString(rec.envelope.payload)
            r = p.reliability
            count += 1
            reliable += r.flag == floorpose_pb2.Reliability.RELIABLE
            print(f"{p.source_stamp_ns * 1e-9:.3f} {p.x:.6f} {p.y:.6f} {p.heading:.6f} "
                  f"{p.floor or '-'} {p.alignment_version} {flag_name(r.flag)} "
                  f"{r.probability:.3f} {r.reason or '-'}")
    except (OSError, ValueError, DecodeError) as e:
        sys.exit(f"plan_poses.py: {e}")
    share = 100.0 * reliable / count if count else math.nan
    print(f"# {count} plan poses, {reliable} RELIABLE ({share:.1f}%)")


if __name__ == "__main__":
    main()
