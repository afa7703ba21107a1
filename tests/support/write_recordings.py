#!/usr/bin/python3
"""Writes one IMU recording in every format calstand imports, each by a writer independent of
calstand's readers, and the same samples as a calstand-import/2 folder (the reference).

    write_recordings.py OUT [--samples N] [--seed S]
    write_recordings.py --from-csv FOLDER OUT.mcap   (a calstand-import/2 folder as MCAP)

OUT/csv/                 meta.json + samples.csv (calstand-import/2, rad/s and m/s^2)
OUT/zstd.mcap, lz4.mcap, none.mcap   MCAP from the specification (mcap.dev/spec): /imu/data
                         (sensor_msgs/msg/Imu, cdr) and /status (std_msgs/msg/String), chunked,
                         with a summary (schemas, channels, statistics)
OUT/nosummary.mcap       the same uncompressed, without a summary (readers must scan)
OUT/ros1.mcap            /imu/data in the ros1 encoding (ros1msg schema)
OUT/two_imu.mcap         two IMU channels (/imu/data and /imu2)
OUT/mcap_bag/            a ROS 2 bag with the mcap storage, split in two files (the second
                         without a summary)
OUT/db3/                 a ROS 2 bag: metadata.yaml + bag_0.db3 (rosbag2's sqlite3 schema, CDR
                         encoded by hand); with /status too
OUT/none.bag, bz2.bag, lz4.bag   ROS 1 bags written by Debian's python3-rosbag (raw messages),
                         when it is installed (else a writer from the bag format 2.0 page)
OUT/euroc/mav0/imu0/     data.csv + sensor.yaml (EuRoC/TUM-VI)

The stamps have awkward nanoseconds, a gap and one out-of-order pair; the values have awkward
digits. Compression modules (python3-zstandard, python3-lz4) are optional: a format whose
module is missing is not written (its file is absent).
"""

import os
import random
import sqlite3
import struct
import sys
import zlib

IMU_MSG = """std_msgs/Header header
geometry_msgs/Quaternion orientation
float64[9] orientation_covariance
geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance
geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance
"""
IMU_MD5 = "6a62c6daae103f4ff57a132d6f95cec2"  # sensor_msgs/Imu (ROS 1)


def make_samples(n, seed):
    rnd = random.Random(seed)
    sec0, ns = 1700000000, 123456789
    out = []
    for i in range(n):
        if i == n // 2:
            ns += 37_000_000  # a gap of about 8 periods
        ns += 5_000_000 + rnd.randint(-20_000, 20_000)  # 200 Hz with jitter
        stamp_ns = sec0 * 10**9 + ns
        gyro = [rnd.gauss(0.0, 0.01) + (1.0 / 3.0 if k == 2 else 0.0) for k in range(3)]
        accel = [rnd.gauss(0.0, 0.02) + (9.80665 if k == 2 else 1e-17) for k in range(3)]
        out.append([stamp_ns, gyro, accel])
    # One out-of-order pair of stamps.
    k = n // 3
    out[k][0], out[k + 1][0] = out[k + 1][0], out[k][0]
    # The receive (log) time: after the latest stamp so far, so that a recorder's time order is
    # the order of the samples.
    latest = 0
    for s in out:
        latest = max(latest, s[0])
        s.append(latest + 300_000)
    return out


def split(stamp_ns):
    return stamp_ns // 10**9, stamp_ns % 10**9


def seconds(stamp_ns):
    sec, nsec = split(stamp_ns)
    return sec + nsec * 1e-9  # the same operation as calstand's readers


def write_csv(out, samples):
    os.makedirs(os.path.join(out, "csv"), exist_ok=True)
    with open(os.path.join(out, "csv", "meta.json"), "w") as f:
        f.write('{"format": "calstand-import/2", "site": {"latitude_deg": 45.0, "height_m": 0.0, '
                '"gravity_mps2": 9.8062}, "sample_rate_hz": 200, '
                '"units": {"gyro": "rad/s", "accel": "m/s^2", "time": "s"}}\n')
    with open(os.path.join(out, "csv", "samples.csv"), "w") as f:
        f.write("t,gx,gy,gz,ax,ay,az\n")
        for stamp, g, a, _ in samples:
            f.write(",".join(repr(v) for v in [seconds(stamp)] + g + a) + "\n")


def imu_values(g, a):
    return [0.0, 0.0, 0.0, 1.0] + [0.0] * 9 + g + [0.0] * 9 + a + [0.0] * 9


def cdr_imu(stamp, g, a, frame=b"imu_link"):
    """sensor_msgs/msg/Imu in CDR: encapsulation 00 01 (little-endian), then the fields aligned
    to their size from the end of the encapsulation header."""
    sec, nsec = split(stamp)
    body = struct.pack("<iII", sec, nsec, len(frame) + 1) + frame + b"\0"
    body += b"\0" * ((8 - len(body) % 8) % 8)
    body += struct.pack("<37d", *imu_values(g, a))
    return b"\x00\x01\x00\x00" + body


def cdr_string(text):
    s = text.encode()
    return b"\x00\x01\x00\x00" + struct.pack("<I", len(s) + 1) + s + b"\0"


def ros1_imu(seq, stamp, g, a, frame=b"imu_link"):
    sec, nsec = split(stamp)
    return struct.pack("<IIII", seq, sec, nsec, len(frame)) + frame + struct.pack(
        "<37d", *imu_values(g, a))


# --- MCAP (mcap.dev/spec) --------------------------------------------------------------------
MAGIC = b"\x89MCAP0\r\n"


def rec(op, content):
    return struct.pack("<BQ", op, len(content)) + content


def s32(text):
    b = text.encode() if isinstance(text, str) else text
    return struct.pack("<I", len(b)) + b


def write_mcap(path, channels, messages, compression="zstd", summary=True, chunk_messages=300,
               corrupt_crc=False):
    """channels: [(id, topic, schema_name, schema_encoding, message_encoding)];
    messages: [(channel_id, log_time_ns, data)]."""
    schemas = {}
    defs = b""
    for cid, topic, sname, senc, menc in channels:
        if sname not in schemas:
            schemas[sname] = len(schemas) + 1
            defs += rec(0x03, struct.pack("<H", schemas[sname]) + s32(sname) + s32(senc) +
                        s32(IMU_MSG if "Imu" in sname else "string data\n"))
        defs += rec(0x04, struct.pack("<HH", cid, schemas[sname]) + s32(topic) + s32(menc) +
                    struct.pack("<I", 0))
    out = bytearray(MAGIC)
    out += rec(0x01, s32("ros2") + s32("calstand test writer"))
    counts = {}
    for start in range(0, len(messages), chunk_messages):
        part = messages[start:start + chunk_messages]
        records = defs if start == 0 else b""
        for seq, (cid, t, data) in enumerate(part):
            records += rec(0x05, struct.pack("<HIQQ", cid, seq, t, t) + data)
            counts[cid] = counts.get(cid, 0) + 1
        crc = zlib.crc32(records)
        if corrupt_crc and start == chunk_messages:
            crc ^= 1
        if compression == "zstd":
            import zstandard
            packed = zstandard.ZstdCompressor().compress(records)
        elif compression == "lz4":
            import lz4.frame
            packed = lz4.frame.compress(records)
        else:
            packed = records
        times = [t for _, t, _ in part]
        out += rec(0x06, struct.pack("<QQQI", min(times), max(times), len(records), crc) +
                   s32(compression) + struct.pack("<Q", len(packed)) + packed)
    out += rec(0x0F, struct.pack("<I", 0))
    summary_start = 0
    if summary:
        summary_start = len(out)
        out += defs
        times = [t for _, t, _ in messages]
        stats = b"".join(struct.pack("<HQ", cid, n) for cid, n in sorted(counts.items()))
        out += rec(0x0B, struct.pack("<QHIIIIQQ", len(messages), len(schemas), len(channels), 0, 0,
                                     (len(messages) + chunk_messages - 1) // chunk_messages,
                                     min(times), max(times)) + s32(stats))
    out += rec(0x02, struct.pack("<QQI", summary_start, 0, 0))
    out += MAGIC
    with open(path, "wb") as f:
        f.write(out)


def status_messages(samples):
    return [(2, s[3] + 1000, cdr_string("ok %d" % i)) for i, s in enumerate(samples[::50])]


def merge_by_time(a, b):
    return sorted(a + b, key=lambda m: m[1])


def write_mcap_bag(out):
    """A ROS 2 bag folder with the mcap storage plugin: metadata.yaml naming two MCAP files
    (the recording split in two, as `ros2 bag record --max-bag-size` does)."""
    folder = os.path.join(out, "mcap_bag")
    os.makedirs(folder, exist_ok=True)
    return folder


def write_mcaps(out, samples):
    imu = [(1, recv, cdr_imu(stamp, g, a)) for stamp, g, a, recv in samples]
    channels = [(1, "/imu/data", "sensor_msgs/msg/Imu", "ros2msg", "cdr"),
                (2, "/status", "std_msgs/msg/String", "ros2msg", "cdr")]
    messages = merge_by_time(imu, status_messages(samples))
    for comp in ("zstd", "lz4", ""):
        try:
            write_mcap(os.path.join(out, (comp or "none") + ".mcap"), channels, messages, comp)
        except ImportError:
            pass
    write_mcap(os.path.join(out, "nosummary.mcap"), channels, messages, "", summary=False)
    bag = write_mcap_bag(out)
    half = len(messages) // 2
    write_mcap(os.path.join(bag, "bag_0.mcap"), channels, messages[:half], "")
    write_mcap(os.path.join(bag, "bag_1.mcap"), channels, messages[half:], "", summary=False)
    with open(os.path.join(bag, "metadata.yaml"), "w") as f:
        f.write("rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: mcap\n"
                "  relative_file_paths:\n    - bag_0.mcap\n    - bag_1.mcap\n")
    write_mcap(os.path.join(out, "crc.mcap"), channels, messages, "", corrupt_crc=True)
    ros1 = [(1, recv, ros1_imu(i, stamp, g, a)) for i, (stamp, g, a, recv) in enumerate(samples)]
    write_mcap(os.path.join(out, "ros1.mcap"),
               [(1, "/imu/data", "sensor_msgs/Imu", "ros1msg", "ros1")], ros1, "")
    two = merge_by_time(imu, [(3, m[1] + 7, m[2]) for m in imu])
    write_mcap(os.path.join(out, "two_imu.mcap"),
               channels[:1] + [(3, "/imu2", "sensor_msgs/msg/Imu", "ros2msg", "cdr")], two, "")


# --- ROS 2 bag, sqlite3 storage (rosbag2_storage_default_plugins) ------------------------------
def write_db3(out, samples):
    folder = os.path.join(out, "db3")
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, "bag_0.db3")
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    db.execute("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL)")
    db.execute("CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, "
               "metadata TEXT NOT NULL)")
    db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
               "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL, "
               "type_description_hash TEXT NOT NULL)")
    db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
               "timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
    db.execute("CREATE INDEX timestamp_idx ON messages (timestamp ASC)")
    db.execute("INSERT INTO topics VALUES (1, '/status', 'std_msgs/msg/String', 'cdr', '', '')")
    db.execute("INSERT INTO topics VALUES (2, '/imu/data', 'sensor_msgs/msg/Imu', 'cdr', '', '')")
    imu = [(2, recv, cdr_imu(stamp, g, a)) for stamp, g, a, recv in samples]
    status = [(1, m[1], m[2]) for m in status_messages(samples)]
    db.executemany("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)",
                   merge_by_time(imu, status))
    db.commit()
    db.close()
    with open(os.path.join(folder, "metadata.yaml"), "w") as f:
        f.write("rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: sqlite3\n"
                "  duration:\n    nanoseconds: %d\n  relative_file_paths:\n    - bag_0.db3\n"
                "  message_count: %d\n" % (samples[-1][3] - samples[0][3], len(samples)))


# --- ROS 1 bag -------------------------------------------------------------------------------
class ImuType:
    _md5sum = IMU_MD5
    _full_text = IMU_MSG
    _type = "sensor_msgs/Imu"


def write_ros1_bags(out, samples):
    try:
        import rosbag
        import genpy
    except ImportError:
        return
    for comp in ("none", "bz2", "lz4"):
        path = os.path.join(out, comp + ".bag")
        with rosbag.Bag(path, "w", compression=comp, chunk_threshold=64 * 1024) as bag:
            for i, (stamp, g, a, recv) in enumerate(samples):
                # Receive time later than the header stamp: readers must use the stamp.
                t = genpy.Time(*split(recv))
                bag.write("/imu/data", ("sensor_msgs/Imu", ros1_imu(i, stamp, g, a), IMU_MD5,
                                        ImuType), t, raw=True)


# --- EuRoC -----------------------------------------------------------------------------------
def write_euroc(out, samples):
    folder = os.path.join(out, "euroc", "mav0", "imu0")
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "data.csv"), "w") as f:
        f.write("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n")
        for stamp, g, a, _ in samples:
            f.write(",".join([str(stamp)] + [repr(v) for v in g + a]) + "\n")
    with open(os.path.join(folder, "sensor.yaml"), "w") as f:
        f.write("# General sensor definitions.\nsensor_type: imu\ncomment: test IMU\n"
                "rate_hz: 200\n")


def csv_to_mcap(folder, path):
    """A calstand-import/2 folder's samples (t, gx..az in its units) as an MCAP file with zstd
    chunks (uncompressed without python3-zstandard): the same recording as a ROS 2 recorder
    would have written it (angular rate in rad/s, stamps in sec + nanosec)."""
    import csv
    import json
    import math
    meta = json.load(open(os.path.join(folder, "meta.json")))
    gyro_unit = meta["units"]["gyro"]
    scale = {"rad/s": 1.0, "deg/s": math.pi / 180.0}[gyro_unit]
    accel = {"m/s^2": 1.0, "g": 9.80665}[meta["units"]["accel"]]
    messages = []
    with open(os.path.join(folder, "samples.csv")) as f:
        for row in csv.DictReader(f):
            ns = round(float(row["t"]) * 1e9)
            g = [float(row[k]) * scale for k in ("gx", "gy", "gz")]
            a = [float(row[k]) * accel for k in ("ax", "ay", "az")]
            messages.append((1, ns, cdr_imu(ns, g, a)))
    try:
        import zstandard  # noqa: F401
        comp = "zstd"
    except ImportError:
        comp = ""
    write_mcap(path, [(1, "/imu/data", "sensor_msgs/msg/Imu", "ros2msg", "cdr")], messages, comp,
               chunk_messages=3000)


def main():
    args = sys.argv[1:]
    if args[0] == "--from-csv":
        csv_to_mcap(args[1], args[2])
        return
    out = args[0]
    n = int(args[args.index("--samples") + 1]) if "--samples" in args else 2000
    seed = int(args[args.index("--seed") + 1]) if "--seed" in args else 7
    os.makedirs(out, exist_ok=True)
    samples = make_samples(n, seed)
    write_csv(out, samples)
    write_mcaps(out, samples)
    write_db3(out, samples)
    write_ros1_bags(out, samples)
    write_euroc(out, samples)


if __name__ == "__main__":
    main()
