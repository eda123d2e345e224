"""A subscriber of the run's firings on the PyPI `eclipse-zenoh` package (not our code):
connects to the router given as argv[1] as a client, subscribes to `*/gspn/firings/**`
(any domain, any type hash), and prints `seq transition key attachment-seq` for each
firing, decoding the CDR payload by hand (header 00 01 00 00, then gspn_msgs/Firing: a
std_msgs/Header, float64 model_time, uint64 seq, the transition string, …) and the attachment with zenoh's own deserializer as rmw_zenoh writes it
(int64 sequence number, int64 source timestamp, the 16-byte GID as a sequence).
Prints `ready` once subscribed; exits after argv[2] firings or argv[3] seconds."""

import json
import struct
import sys
import time

import zenoh
from zenoh.ext import Int64, UInt8, z_deserialize


def main() -> None:
    endpoint, want, limit = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    with zenoh.open(conf) as session:
        sub = session.declare_subscriber("*/gspn/firings/**")
        print("ready", flush=True)
        got, end = 0, time.monotonic() + limit
        while got < want and time.monotonic() < end:
            sample = sub.try_recv()
            if sample is None:
                time.sleep(0.005)
                continue
            b = sample.payload.to_bytes()
            assert b[:4] == b"\x00\x01\x00\x00", b[:4]
            body = b[4:]
            # header.stamp (int32 sec, uint32 nanosec), header.frame_id (uint32 length with
            # the NUL, the bytes), then model_time aligned at 8 of the body.
            (frame_len,) = struct.unpack_from("<I", body, 8)
            pos = 12 + frame_len
            pos += (-pos) % 8
            model_time, seq = struct.unpack_from("<dQ", body, pos)
            (n,) = struct.unpack_from("<I", body, pos + 16)
            name = body[pos + 20 : pos + 20 + n - 1].decode()
            assert model_time >= 0.0, model_time
            att_seq, _stamp, gid = z_deserialize(
                tuple[Int64, Int64, list[UInt8]], sample.attachment
            )
            assert len(gid) == 16, gid
            print(seq, name, str(sample.key_expr), att_seq, flush=True)
            got += 1


if __name__ == "__main__":
    main()
