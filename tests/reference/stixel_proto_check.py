"""Decodes a .stx1 file written by our C++ encoder with the protobuf library,
checks that protobuf serialises the parsed message to exactly the same bytes,
and dumps every field for the C++ test to compare. With --json, also parses our
JSON export with google.protobuf.json_format and checks it is the same message.
Exit status 1 with a message on any mismatch."""
import sys

import stixel_refutil as ru

np = ru.import_numpy()


def main(argv):
    a = ru.args(argv, [("--pb-dir", dict(required=True)), ("--input", dict(required=True)),
                       ("--dump", dict(required=True)), ("--json", dict(default=None))],
                need_out=False)
    pb = ru.load_protobuf_module(a.pb_dir)
    from google.protobuf import json_format
    data = open(a.input, "rb").read()
    msg = pb.StixelWorld()
    msg.ParseFromString(data)
    again = msg.SerializeToString()
    if again != data:
        at = next((i for i in range(min(len(again), len(data))) if again[i] != data[i]),
                  min(len(again), len(data)))
        sys.exit("error: %s: protobuf re-serialises to %d bytes, ours has %d; first difference at byte %d"
                 % (a.input, len(again), len(data), at))
    if a.json:
        from_json = json_format.Parse(open(a.json, encoding="utf-8").read(), pb.StixelWorld())
        if from_json.SerializeToString() != data:
            sys.exit("error: %s: json_format.Parse gives a different message than the .stx1" % a.json)
    tensors, meta = ru.dump_world(np, msg)
    ru.save(a.dump, tensors, meta)


if __name__ == "__main__":
    main(sys.argv[1:])
