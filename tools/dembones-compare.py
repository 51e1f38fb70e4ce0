#!/usr/bin/env python3
"""Side by side: surfcap's skinned rigs (`surfcap rig`, SSDR in Rust) against EA's Dem Bones
(PyPI `py-dem-bones`, the C++ SSDR library's bindings) on the same frames and bone counts.

Subjects: the crane and samba (vlasic2008), the KayKit knight (all its clips, one subject), the
CMU-driven mannequin (`surfcap make mannequin --bvh` on subject 16's walk and jog). For each subject and
bone count:

- ours: `surfcap rig SUBJECT --bones B --max-influences 4 -o X.glb --json`; its error is measured
  here again from the written glb (joints' animation, inverse bind matrices, JOINTS_0/WEIGHTS_0,
  evaluated with numpy as an engine does) against the source frames; time is the report's
  decomposition time (the whole command's wall time beside it);
- Dem Bones: `py_dem_bones.solve_skinning(rest, frames, B, faces=..., max_influences=4)` with its
  default iterations; error from its weights and transforms; time of the call. It writes no file,
  so its size is that of the same glTF skin layout (mesh, 4 joints and weights per vertex, B
  joints' translation and rotation per frame) computed from its sizes.

Writes a Markdown table (docs/results/rig.md) with the command that made it.

    tools/venv/bin/python tools/dembones-compare.py --surfcap target/release/surfcap \
        --out docs/results/rig.md
"""

import argparse
import hashlib
import json
import os
import resource
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def data_dir():
    env = os.environ.get("SURFCAP_DATA")
    if env:
        return Path(env)
    return Path(__file__).resolve().parent.parent.parent / "shared" / "data"


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(map(str, cmd))} failed ({p.returncode}):\n{p.stderr}")
    return p.stdout


def read_glb(path):
    b = Path(path).read_bytes()
    magic, _, _ = struct.unpack_from("<4sII", b, 0)
    assert magic == b"glTF", path
    jlen, jtype = struct.unpack_from("<I4s", b, 12)
    doc = json.loads(b[20 : 20 + jlen])
    blen, _ = struct.unpack_from("<I4s", b, 20 + jlen)
    blob = b[28 + jlen : 28 + jlen + blen]
    comp = {5121: np.uint8, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}

    def acc(i):
        a = doc["accessors"][i]
        v = doc["bufferViews"][a["bufferView"]]
        n, w = a["count"], width[a["type"]]
        off = v.get("byteOffset", 0) + a.get("byteOffset", 0)
        return np.frombuffer(blob, comp[a["componentType"]], n * w, off).reshape(n, w)

    return doc, acc


def quat_to_matrix(q):
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    m = np.empty(q.shape[:-1] + (3, 3))
    m[..., 0, 0] = 1 - 2 * (y * y + z * z)
    m[..., 0, 1] = 2 * (x * y - z * w)
    m[..., 0, 2] = 2 * (x * z + y * w)
    m[..., 1, 0] = 2 * (x * y + z * w)
    m[..., 1, 1] = 1 - 2 * (x * x + z * z)
    m[..., 1, 2] = 2 * (y * z - x * w)
    m[..., 2, 0] = 2 * (x * z - y * w)
    m[..., 2, 1] = 2 * (y * z + x * w)
    m[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return m


def glb_skinned_frames(path):
    """Every animation's frames as an engine plays them, in the mesh's own coordinates (the
    up-axis root rotation, applied to the joints, is taken off again)."""
    doc, acc = read_glb(path)
    skin = doc["skins"][0]
    joints = skin["joints"]
    ibm = acc(skin["inverseBindMatrices"]).reshape(-1, 4, 4).transpose(0, 2, 1).astype(np.float64)
    prim = doc["meshes"][0]["primitives"][0]
    rest = acc(prim["attributes"]["POSITION"]).astype(np.float64)
    jn = [acc(prim["attributes"][f"JOINTS_{s}"]).astype(np.int64) for s in range(2) if f"JOINTS_{s}" in prim["attributes"]]
    wt = [acc(prim["attributes"][f"WEIGHTS_{s}"]).astype(np.float64) for s in range(2) if f"WEIGHTS_{s}" in prim["attributes"]]
    jn, wt = np.concatenate(jn, 1), np.concatenate(wt, 1)
    out = []
    for anim in doc["animations"]:
        n = None
        trs = {}
        for ch in anim["channels"]:
            s = anim["samplers"][ch["sampler"]]
            vals = acc(s["output"]).astype(np.float64)
            n = len(vals)
            trs[(ch["target"]["node"], ch["target"]["path"])] = vals
        for f in range(n):
            mats = np.zeros((len(joints), 4, 4))
            for k, node in enumerate(joints):
                m = np.eye(4)
                m[:3, :3] = quat_to_matrix(trs[(node, "rotation")][f])
                m[:3, 3] = trs[(node, "translation")][f]
                mats[k] = m @ ibm[k]
            restp = np.c_[rest, np.ones(len(rest))]
            per = np.einsum("vkij,vj->vki", mats[jn][:, :, :3, :], restp)
            out.append(np.einsum("vk,vki->vi", wt, per))
    return np.array(out)


def errors(rec, src, height):
    e = np.linalg.norm(rec - src, axis=2)
    rms = float(np.sqrt((e**2).mean()))
    return {"rms": rms, "max": float(e.max()), "rms_pct": 100 * rms / height, "max_pct": 100 * float(e.max()) / height}


def skin_glb_bytes(v, t, bones, frames, sequences):
    """Binary payload of the glTF skin layout surfcap writes: indices, positions, 4 joints (u8)
    and 4 weights (f32) per vertex, inverse bind matrices, per sequence key times and each bone's
    translation and rotation per frame (JSON not counted)."""
    return 12 * t + 12 * v + 4 * v + 16 * v + 64 * bones + 4 * frames + 28 * bones * frames


def load_npy_subject(folder, seqs):
    """Frames (sequences `seqs` in that order), faces and sequence sizes of an `surfcap export
    --format npy` folder."""
    frames = [np.load(folder / s / "positions.npy").astype(np.float64) for s in seqs]
    faces = [
        [int(x.split("/")[0]) - 1 for x in line.split()[1:]]
        for line in (folder / seqs[0] / "template.obj").read_text().splitlines()
        if line.startswith("f ")
    ]
    return np.concatenate(frames), faces, [len(f) for f in frames], seqs


def dembones(frames, faces, b, sizes, cache, args, name):
    """Dem Bones on the frames (or its cached result for the same frames and bone count)."""
    import py_dem_bones

    key = f"{hashlib.sha1(np.ascontiguousarray(frames, dtype=np.float32).tobytes()).hexdigest()}-{b}"
    if key not in cache and args.dembones_cache and Path(args.dembones_cache).exists():
        # An --only-dembones run started beside this one may have filled it since.
        cache.update(json.loads(Path(args.dembones_cache).read_text()))
    if key in cache:
        return cache[key]
    nf, nv = frames.shape[:2]
    t0, c0 = time.perf_counter(), time.process_time()
    r = py_dem_bones.solve_skinning(frames[0], frames, b, faces=faces, max_influences=4)
    secs, cpu = time.perf_counter() - t0, time.process_time() - c0
    w, m = r.weights, r.transforms
    restp = np.c_[frames[0], np.ones(nv)]
    rec = np.einsum("bv,fbij,vj->fvi", w, m[:, :, :3, :], restp)
    e = np.linalg.norm(rec - frames, axis=2)
    used = int((w.sum(1) > 0).sum())
    out = {"rms": float(np.sqrt((e**2).mean())), "max": float(e.max()), "seconds": secs, "cpu_seconds": cpu,
           "bytes": skin_glb_bytes(nv, len(faces), used, nf, len(sizes)), "bones": used,
           "measured": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "load": os.getloadavg()[0]}
    print(json.dumps({"dembones": name, "bones": b, **out}), flush=True)
    cache[key] = out
    if args.dembones_cache:
        Path(args.dembones_cache).write_text(json.dumps(cache, indent=1))
    return out


def children_cpu():
    """CPU seconds (user and system, every thread) of the finished child processes."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--surfcap", default="target/release/surfcap")
    ap.add_argument("--out", default="docs/results/rig.md")
    ap.add_argument("--bones", default="16,32")
    ap.add_argument("--subjects", default="crane,samba,knight,cmu-mannequin")
    ap.add_argument("--iterations", type=int, default=None, help="our iterations (default: surfcap rig's)")
    ap.add_argument("--dembones-cache", default=None,
                    help="JSON file of Dem Bones results by frames hash and bone count: reused when the frames are the same")
    ap.add_argument("--only-dembones", action="store_true",
                    help="run Dem Bones only (frames in the subjects' own order) and fill --dembones-cache")
    args = ap.parse_args()
    cache = {}
    if args.dembones_cache and Path(args.dembones_cache).exists():
        cache = json.loads(Path(args.dembones_cache).read_text())
    import py_dem_bones

    data = data_dir()
    tmp = Path(tempfile.mkdtemp(prefix="dembones-compare-"))
    exe = str(Path(args.surfcap).resolve())
    subjects = {}
    for name in args.subjects.split(","):
        if name in ("crane", "samba"):
            subjects[name] = [str(data / "vlasic2008" / name)]
        elif name == "knight":
            k = data / "kaykit_adventurers"
            clips = sorted(str(p) for p in k.iterdir() if p.name.startswith("knight_"))
            subj = tmp / "knight.subject"
            run([exe, "--quiet", "import", *clips, "-o", str(subj)])
            subjects[name] = [str(subj)]
        elif name == "cmu-mannequin":
            subj = tmp / "cmu.subject"
            bvh = data / "cmu_bvh"
            run([exe, "--quiet", "make", "mannequin", "--bvh", str(bvh / "16_15.bvh"), str(bvh / "16_36.bvh"), "-o", str(subj)])
            subjects[name] = [str(subj)]
        else:
            sys.exit(f"unknown subject {name}")
    rows = []
    for name, src in subjects.items():
        npy = tmp / f"{name}-npy"
        run([exe, "--quiet", "export", *src, "--format", "npy", "-o", str(npy)])
        frames = None
        if args.only_dembones:
            meta = json.loads((npy / "meta.json").read_text())
            order = list(meta["sequences"])  # folders in the subject's order
            frames, faces, sizes, seqs = load_npy_subject(npy, order)
            height = None
        for b in [int(x) for x in args.bones.split(",")]:
            if args.only_dembones:
                dembones(frames, faces, b, sizes, cache, args, name)
                continue
            glb = tmp / f"{name}-{b}.glb"
            cmd = [exe, "--json", "rig", *src, "--bones", str(b), "--max-influences", "4", "-o", str(glb)]
            if args.iterations is not None:
                cmd += ["--iterations", str(args.iterations)]
            t0, c0 = time.perf_counter(), children_cpu()
            rep = json.loads(run(cmd))["rig"]
            wall, cpu = time.perf_counter() - t0, children_cpu() - c0
            height = rep["height"]
            if frames is None:
                # The subject's sequences in the order the rig's animations have them.
                order = [a["name"] for a in read_glb(glb)[0]["animations"]]
                frames, faces, sizes, seqs = load_npy_subject(npy, order)
                nf, nv = frames.shape[:2]
            rec = glb_skinned_frames(glb)
            ours = errors(rec, frames, height)
            assert abs(ours["rms"] - rep["rms"]) <= 1e-3 * height, (ours, rep["rms"])
            ours.update(seconds=rep["decomposition_seconds"], wall=wall, cpu_seconds=cpu, bytes=glb.stat().st_size, bones=rep["bones"])

            db = dict(dembones(frames, faces, b, sizes, cache, args, name))
            db.update(rms_pct=100 * db["rms"] / height, max_pct=100 * db["max"] / height)
            row = dict(subject=name, frames=nf, vertices=nv, bones=b, height=height, units=rep["units"],
                       morph=rep["morph_glb_bytes"], ours=ours, dembones=db)
            print(json.dumps(row), flush=True)
            rows.append(row)
            write_table(rows, args)  # after every row: a long run leaves what it measured
    if not args.only_dembones:
        write_table(rows, args)


def cpu_text(d):
    return f"{d['cpu_seconds']:.1f} s" if "cpu_seconds" in d else "-"


def write_table(rows, args):
    cmd = "tools/venv/bin/python tools/dembones-compare.py --surfcap target/release/surfcap --out " + args.out
    if args.bones != "16,32":
        cmd += f" --bones {args.bones}"
    if args.subjects != "crane,samba,knight,cmu-mannequin":
        cmd += f" --subjects {args.subjects}"
    if args.iterations is not None:
        cmd += f" --iterations {args.iterations}"
    if args.dembones_cache:
        cmd += f" --dembones-cache {args.dembones_cache}"
    lines = [
        "# Skinned rigs: surfcap (SSDR in Rust) beside Dem Bones",
        "",
        "Made by (from the checkout, after `cargo build --release -p surfcap-cli`, with",
        "`py-dem-bones` in tools/venv; a 2-core machine, both using both cores):",
        "",
        "```console",
        cmd,
        "```",
        "",
        "Same frames, same bone count, at most 4 bones per vertex, for both. Error: per-vertex distance to",
        "the source over every frame, RMS and max, in the subject's units and % of its height (extent",
        "along the up axis in the first frame); ours measured from the written glb as an engine plays",
        "it. Time: ours the decomposition (`decomposition_seconds` of `surfcap rig --json`; the whole",
        "command, loading and writing included, in brackets), Dem Bones the `solve_skinning` call",
        "(its default 30 iterations). Size: ours the glb file; Dem Bones writes no file, so the binary",
        "payload of the same skin layout for its bones and frames. Morph: `surfcap export --format glb`.",
        "CPU: processor time of every thread (ours of the whole command; Dem Bones' of the call), which",
        "depends far less on the machine's load than wall time; '-' for Dem Bones runs cached before",
        "it was recorded.",
        "",
        "| subject | frames x vertices | bones | ours RMS | Dem Bones RMS | ours max | Dem Bones max | ours time | Dem Bones time | speed-up | ours CPU | Dem Bones CPU | ours size | Dem Bones size | morph glb |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        o, d, u = r["ours"], r["dembones"], r["units"]
        lines.append(
            f"| {r['subject']} | {r['frames']} x {r['vertices']} | {r['bones']} ({d['bones']} used by Dem Bones) "
            f"| {o['rms']:.4f} {u} ({o['rms_pct']:.2f}%) | {d['rms']:.4f} {u} ({d['rms_pct']:.2f}%) "
            f"| {o['max']:.3f} {u} ({o['max_pct']:.1f}%) | {d['max']:.3f} {u} ({d['max_pct']:.1f}%) "
            f"| {o['seconds']:.1f} s ({o['wall']:.1f} s) | {d['seconds']:.1f} s | {d['seconds'] / o['seconds']:.1f}x "
            f"| {o['cpu_seconds']:.1f} s | {cpu_text(d)} "
            f"| {o['bytes'] / 1e6:.2f} MB | {d['bytes'] / 1e6:.2f} MB | {r['morph'] / 1e6:.1f} MB |"
        )
    lines.append("")
    lines.append("Dem Bones runs (measured when, and the machine's 1-minute load average then):")
    lines.append("")
    for r in rows:
        d = r["dembones"]
        if "measured" in d:
            lines.append(f"- {r['subject']}, {r['bones']} bones: {d['measured']}, load {d['load']:.1f}")
    lines.append("")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
