"""Loads a glTF/GLB tree in Blender (the `bpy` module) and plays its animation: proof that the file
imports and deforms in Blender. Manual check, not part of CI.

Setup (Blender 5.2's bpy wheel is built for Python 3.13 only; ~400 MB download, ~1 GB installed):
    python3.13 -m venv /tmp/bpyvenv && /tmp/bpyvenv/bin/pip install bpy
Usage:
    /tmp/bpyvenv/bin/python tools/blender_check.py FILE.glb [--frames N] [--dump FILE.npz]

Steps: factory settings (empty scene), bpy.ops.import_scene.gltf, then list objects (meshes,
armatures, their modifiers and parents), actions (frame range, F-curve count, slots) and NLA
tracks, the scene's frame range and fps (the importer turns glTF seconds into frames at the scene's
fps, 24 by default: frame = t · fps, so time_s = frame / fps). Then for N frames spread evenly over the animated range
(first to last key, both included) it sets the frame, evaluates the depsgraph and reads the
world-space positions of every evaluated (armature-deformed) mesh vertex.

Prints one JSON document: objects, vertex counts, per-frame bounds, the largest displacement of
any vertex from its position on the first sampled frame, and between consecutive sampled frames.
Positions and bounds are given in glTF axes (Y up: x, y, z = Blender x, z, -y; the importer turns
+Y-up into Blender's +Z-up), so they compare directly with frond's and three.js's numbers.
`--dump` also writes the positions (glTF axes) per object and frame to a .npz file
(arrays `<object>@<k>`, plus `frames` and `times`), for point-set comparisons.

Exit 1 with a message when the import fails or yields no mesh.
"""

import argparse
import json
import os
import sys

import numpy as np


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("file", help="a .glb or .gltf file")
    p.add_argument("--frames", type=int, default=5, help="frames to sample (default 5)")
    p.add_argument("--dump", help="write per-frame world positions (glTF axes) to this .npz")
    return p.parse_args(argv)


def to_gltf_axes(co):
    """Blender Z-up (x, y, z) -> glTF Y-up (x, z, -y)."""
    return np.stack([co[:, 0], co[:, 2], -co[:, 1]], axis=1)


def action_info(action):
    info = {
        "name": action.name,
        "frame_range": [float(action.frame_range[0]), float(action.frame_range[1])],
        "users": action.users,
    }
    fcurves = 0
    # Blender 4.4+ layered (slotted) actions; fall back to the legacy list.
    layers = getattr(action, "layers", None)
    if layers is not None and len(layers) > 0:
        for layer in layers:
            for strip in layer.strips:
                for bag in getattr(strip, "channelbags", []):
                    fcurves += len(bag.fcurves)
        info["slots"] = [s.identifier for s in getattr(action, "slots", [])]
    elif hasattr(action, "fcurves"):
        fcurves = len(action.fcurves)
    info["fcurves"] = fcurves
    return info


def world_positions(obj_eval):
    """World-space vertex positions (Blender axes) of an evaluated mesh object."""
    mesh = obj_eval.to_mesh()
    try:
        n = len(mesh.vertices)
        co = np.empty(n * 3, dtype=np.float64)
        mesh.vertices.foreach_get("co", co)
        co = co.reshape(n, 3)
        m = np.array(obj_eval.matrix_world, dtype=np.float64)
        return co @ m[:3, :3].T + m[:3, 3]
    finally:
        obj_eval.to_mesh_clear()


def main(argv):
    args = parse_args(argv)
    try:
        import bpy
    except ImportError as e:
        sys.exit(f"blender_check: cannot import bpy ({e}); pip install bpy (Python 3.13)")

    # Blender and the importer log to file descriptor 1; keep stdout for the JSON summary.
    sys.stdout.flush()
    saved_stdout = os.dup(1)
    os.dup2(2, 1)
    try:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        result = bpy.ops.import_scene.gltf(filepath=args.file)
    except Exception as e:  # the importer raises RuntimeError with its report
        sys.exit(f"blender_check: {args.file}: import failed: {e}")
    finally:
        sys.stdout.flush()
        os.dup2(saved_stdout, 1)
        os.close(saved_stdout)
    if "FINISHED" not in result:
        sys.exit(f"blender_check: {args.file}: import did not finish ({result})")

    scene = bpy.context.scene
    fps = scene.render.fps / scene.render.fps_base
    # The importer adds a display shape for bones (a mesh named "Icosphere"): not tree geometry.
    bone_shapes = {
        pb.custom_shape.name
        for o in scene.objects
        if o.type == "ARMATURE"
        for pb in o.pose.bones
        if pb.custom_shape is not None
    }
    objects = []
    meshes = []
    for obj in sorted(scene.objects, key=lambda o: o.name):
        entry = {
            "name": obj.name,
            "type": obj.type,
            "parent": obj.parent.name if obj.parent else None,
        }
        if obj.name in bone_shapes:
            entry["bone_shape"] = True
        elif obj.type == "MESH":
            entry["vertices"] = len(obj.data.vertices)
            entry["polygons"] = len(obj.data.polygons)
            entry["materials"] = [m.name for m in obj.data.materials if m]
            entry["modifiers"] = [
                {"type": m.type, "object": getattr(getattr(m, "object", None), "name", None)}
                for m in obj.modifiers
            ]
            entry["vertex_groups"] = len(obj.vertex_groups)
            meshes.append(obj)
        elif obj.type == "ARMATURE":
            entry["bones"] = len(obj.data.bones)
        ad = obj.animation_data
        if ad is not None:
            entry["action"] = ad.action.name if ad.action else None
            entry["nla_tracks"] = [
                {"name": t.name, "strips": [s.action.name if s.action else None for s in t.strips]}
                for t in ad.nla_tracks
            ]
        objects.append(entry)
    if not meshes:
        sys.exit(f"blender_check: {args.file}: no mesh object after import")

    actions = [action_info(a) for a in bpy.data.actions]
    if actions:
        lo = min(a["frame_range"][0] for a in actions)
        hi = max(a["frame_range"][1] for a in actions)
    else:
        lo = hi = float(scene.frame_start)
    n = max(1, args.frames)
    frames = [lo + (hi - lo) * k / (n - 1) for k in range(n)] if n > 1 else [lo]

    per_frame = []
    first = {}
    previous = {}
    max_from_first = {o.name: 0.0 for o in meshes}
    max_step = {o.name: 0.0 for o in meshes}
    dump = {}
    for k, f in enumerate(frames):
        whole = int(np.floor(f))
        scene.frame_set(whole, subframe=f - whole)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        record = {"frame": f, "time_s": f / fps, "objects": {}}
        for obj in meshes:
            pos = to_gltf_axes(world_positions(obj.evaluated_get(depsgraph)))
            record["objects"][obj.name] = {
                "vertices": len(pos),
                "min": pos.min(axis=0).round(6).tolist(),
                "max": pos.max(axis=0).round(6).tolist(),
            }
            if obj.name in first and len(first[obj.name]) == len(pos):
                d = float(np.linalg.norm(pos - first[obj.name], axis=1).max())
                s = float(np.linalg.norm(pos - previous[obj.name], axis=1).max())
                max_from_first[obj.name] = max(max_from_first[obj.name], d)
                max_step[obj.name] = max(max_step[obj.name], s)
            else:
                first[obj.name] = pos
            previous[obj.name] = pos
            if args.dump:
                dump[f"{obj.name}@{k}"] = pos.astype(np.float32)
        per_frame.append(record)

    if args.dump:
        np.savez_compressed(
            args.dump,
            frames=np.array(frames),
            times=np.array([f / fps for f in frames]),
            **dump,
        )

    summary = {
        "file": args.file,
        "blender": bpy.app.version_string,
        "objects": objects,
        "mesh_objects": len(meshes),
        "armatures": sum(1 for o in objects if o["type"] == "ARMATURE"),
        "actions": actions,
        "scene_frame_range": [scene.frame_start, scene.frame_end],
        "fps": fps,
        "sampled_frames": per_frame,
        "max_displacement_from_first": max_from_first,
        "max_displacement_between_samples": max_step,
        "moves": any(v > 0.0 for v in max_from_first.values()),
    }
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main(sys.argv[1:])
