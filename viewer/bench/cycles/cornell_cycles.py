# Renders an OBJ/MTL scene (by default Meshlight's Cornell box, data/cornell_box.obj) with Blender Cycles on the
# CPU, with settings chosen to match `meshlight reference` (see README.md beside this file), and prints timings.
#
#   blender -b --factory-startup --python cornell_cycles.py -- --obj data/cornell_box.obj --out OUT.exr \
#       --spp N --bounces B --width W --height H [--direct-only] [--camera px,py,pz,tx,ty,tz,ux,uy,uz,fov]
#       [--threads T] [--seed S] [--scale F] [--repeat R] [--reference REF.exr]
#
# The OBJ is read by this script (v, f, usemtl, mtllib; MTL Kd, Ke), not by Blender's importer, so that
# coordinates stay as in the file (no axis conversion), times --scale (default 0.001, millimetres to metres: Cycles
# 3.4 picks its triangle-light sampling with a scale-dependent test, and in millimetres it picks spherical-triangle
# sampling everywhere, which comes out up to 3-5 % too dark near the light; see README.md). Materials: Lambert (Diffuse BSDF, roughness 0) with
# colour Kd; where Ke > 0, plus an Emission shader of colour Ke and strength 1 (radiance Ke) on the front
# (counter-clockwise) face only, like Meshlight's emitters.
import argparse
import ctypes
import math
import os
import re
import sys
import tempfile
import time

import bpy
from mathutils import Matrix, Vector

CORNELL_CAMERA = [278, 273, -800, 278, 273, 0, 0, 1, 0, math.degrees(2 * math.atan(12.5 / 35))]


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="cornell_cycles.py")
    p.add_argument("--obj", default="data/cornell_box.obj")
    p.add_argument("--out", required=True, help="linear float EXR")
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--bounces", type=int, default=7,
                   help="Cycles max bounces (0 = direct light only; B = Meshlight --max-depth B+1)")
    p.add_argument("--width", type=int, default=256)
    p.add_argument("--height", type=int, default=256)
    p.add_argument("--direct-only", action="store_true", help="same as --bounces 0")
    p.add_argument("--camera", default=",".join(repr(float(x)) for x in CORNELL_CAMERA),
                   help="px,py,pz,tx,ty,tz,ux,uy,uz,vertical fov in degrees (default: the built-in Cornell box's)")
    p.add_argument("--threads", type=int, default=0, help="0 = every core")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--scale", type=float, default=0.001,
                   help="multiply all coordinates (geometry and camera) by S (default 0.001: millimetres to metres; "
                        "radiance does not depend on it, but Cycles' choice of light sampling does, see README.md)")
    p.add_argument("--repeat", type=int, default=1,
                   help="render R times in this process (timings of warm renders, without Blender start-up)")
    p.add_argument("--serve", action="store_true",
                   help="render jobs read from standard input, one per line, in this one process (for `meshlight "
                        "bench gi`): 'render OUT.exr SPP WIDTH HEIGHT px,py,pz,tx,ty,tz,ux,uy,uz,fov SEED', or "
                        "'quit'; answers '@@cycles ready' once the scene is built and '@@cycles done OUT wall=S "
                        "cpu=S path=S save=S' per job (wall: bpy.ops.render.render, scene sync included; path: "
                        "Cycles' own path-tracing time; save: the EXR write, not in wall)")
    p.add_argument("--reference", help="print the relative RMSE of the image against this EXR (e.g. from "
                   "`meshlight reference`), and that of REF.noise.exr's standard error if it lies beside it")
    a = p.parse_args(argv)
    if a.direct_only:
        a.bounces = 0
    return a


def statements(path):
    """The lines of an OBJ or MTL file, each as its list of words; blank lines and comments left out."""
    with open(path) as f:
        for line in f:
            t = line.split()
            if t and not t[0].startswith("#"):
                yield t


def read_mtl(path):
    mats, cur = {}, None
    for t in statements(path):
        if t[0] == "newmtl":
            cur = mats.setdefault(" ".join(t[1:]), {"Kd": (0.8, 0.8, 0.8), "Ke": (0.0, 0.0, 0.0)})
        elif t[0] in ("Kd", "Ke") and cur is not None:
            v = [float(x) for x in t[1:4]]
            cur[t[0]] = tuple(v if len(v) == 3 else [v[0]] * 3)
    return mats


def read_obj(path, scale):
    verts, faces, face_mat, mat_names, mats = [], [], [], [], {}
    cur = None
    for t in statements(path):
        if t[0] == "v":
            verts.append(tuple(scale * float(x) for x in t[1:4]))
        elif t[0] == "f":
            idx = []
            for c in t[1:]:
                i = int(c.split("/")[0])
                idx.append(i - 1 if i > 0 else len(verts) + i)
            if cur is None:
                cur = "default"
                mats.setdefault(cur, {"Kd": (0.8, 0.8, 0.8), "Ke": (0.0, 0.0, 0.0)})
            if cur not in mat_names:
                mat_names.append(cur)
            faces.append(idx)
            face_mat.append(mat_names.index(cur))
        elif t[0] == "usemtl":
            cur = " ".join(t[1:])
        elif t[0] == "mtllib":
            mats.update(read_mtl(os.path.join(os.path.dirname(path), " ".join(t[1:]))))
    return verts, faces, face_mat, [(n, mats[n]) for n in mat_names]


def make_material(name, kd, ke):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    diff = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diff.inputs["Color"].default_value = (*kd, 1.0)
    diff.inputs["Roughness"].default_value = 0.0  # Lambert
    if max(ke) > 0:
        emit = nt.nodes.new("ShaderNodeEmission")
        emit.inputs["Color"].default_value = (*ke, 1.0)
        emit.inputs["Strength"].default_value = 1.0  # radiance = Ke (W/sr/m^2)
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(emit.outputs[0], add.inputs[0])
        nt.links.new(diff.outputs[0], add.inputs[1])
        # Front face only: the back face is the plain diffuse surface.
        geo = nt.nodes.new("ShaderNodeNewGeometry")
        mix = nt.nodes.new("ShaderNodeMixShader")
        nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
        nt.links.new(add.outputs[0], mix.inputs[1])
        nt.links.new(diff.outputs[0], mix.inputs[2])
        nt.links.new(mix.outputs[0], out.inputs["Surface"])
    else:
        nt.links.new(diff.outputs[0], out.inputs["Surface"])
    return m


def place_camera(cam, camera, scale, verts):
    """Sets the camera object from "px,py,pz,tx,ty,tz,ux,uy,uz,fov" (the scene's units, times `scale`; vertical
    field of view in degrees) and its clipping planes from the scene's vertices (already scaled)."""
    # Looks along its local -Z, up +Y.
    c = [float(x) for x in camera.split(",")]
    if len(c) != 10:
        sys.exit(f"camera '{camera}': px,py,pz,tx,ty,tz,ux,uy,uz,fov expected")
    pos, target, up, fov = scale * Vector(c[0:3]), scale * Vector(c[3:6]), Vector(c[6:9]), c[9]
    fwd = (target - pos).normalized()
    right = fwd.cross(up).normalized()
    upv = right.cross(fwd)
    rot = Matrix((right, upv, -fwd)).transposed()
    cam_data = cam.data
    cam_data.type = "PERSP"
    cam_data.sensor_fit = "VERTICAL"
    cam_data.sensor_height = 24.0
    cam_data.lens = 0.5 * cam_data.sensor_height / math.tan(math.radians(fov) / 2)
    diag = (Vector([max(v[i] for v in verts) for i in range(3)]) -
            Vector([min(v[i] for v in verts) for i in range(3)])).length
    far = (pos - Vector([sum(v[i] for v in verts) / len(verts) for i in range(3)])).length + diag
    cam_data.clip_start = 1e-6 * far
    cam_data.clip_end = 10 * far
    cam.matrix_world = Matrix.Translation(pos) @ rot.to_4x4()


def build_scene(a):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    verts, faces, face_mat, mats = read_obj(a.obj, a.scale)
    mesh = bpy.data.meshes.new("scene")
    mesh.from_pydata(verts, [], faces)
    for name, m in mats:
        mesh.materials.append(make_material(name, m["Kd"], m["Ke"]))
    mesh.polygons.foreach_set("material_index", face_mat)
    mesh.polygons.foreach_set("use_smooth", [False] * len(faces))  # geometric normals
    mesh.update()
    obj = bpy.data.objects.new("scene", mesh)
    scene.collection.objects.link(obj)

    cam_data = bpy.data.cameras.new("camera")
    cam = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    place_camera(cam, a.camera, a.scale, verts)
    a.scene_vertices = verts  # --serve places the camera again per job

    world = bpy.data.worlds.new("black")
    world.use_nodes = False
    world.color = (0.0, 0.0, 0.0)
    scene.world = world

    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = a.width, a.height, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.film_transparent = False
    r.use_motion_blur = False
    r.threads_mode = "FIXED" if a.threads > 0 else "AUTO"
    if a.threads > 0:
        r.threads = a.threads
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
    vs = scene.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = "Standard", "None", 0.0, 1.0

    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = a.spp
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.time_limit = 0
    cy.seed = a.seed
    cy.use_animated_seed = False
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.film_exposure = 1.0  # a multiplier: 1 = unchanged
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0  # the default, 10, would clamp
    cy.light_sampling_threshold = 0.0  # the default, 0.01, skips weak light samples
    cy.blur_glossy = 0.0
    cy.max_bounces = a.bounces
    cy.diffuse_bounces = a.bounces
    cy.glossy_bounces = a.bounces
    cy.transmission_bounces = a.bounces
    cy.volume_bounces = 0
    cy.transparent_max_bounces = 0
    cy.min_light_bounces = 0
    cy.min_transparent_bounces = 0
    for opt, val in (("use_light_tree", False), ("use_guiding", False)):  # Blender >= 3.5/3.6 only
        if hasattr(cy, opt):
            setattr(cy, opt, val)
    for vl in scene.view_layers:
        if hasattr(vl, "cycles"):
            vl.cycles.use_denoising = False
    return scene


def loadavg():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def render_capturing_stats():
    """Renders, capturing Blender's status lines (printed by C code to fd 1) to read Cycles' own times from them.

    Returns (wall seconds, CPU seconds of all threads, Cycles' time at the first sample, Cycles' time at
    "Finished", status lines)."""
    libc = ctypes.CDLL(None)
    sys.stdout.flush()
    libc.fflush(None)
    saved = os.dup(1)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), 1)
        try:
            t0, c0 = time.perf_counter(), time.process_time()
            bpy.ops.render.render()
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        finally:
            sys.stdout.flush()
            libc.fflush(None)
            os.dup2(saved, 1)
            os.close(saved)
        tmp.seek(0)
        lines = tmp.read().decode(errors="replace").splitlines()

    def seconds(line):
        m = re.search(r"Time:(?:(\d+):)?(\d+):(\d+\.\d+)", line)
        return None if not m else int(m.group(1) or 0) * 3600 + int(m.group(2)) * 60 + float(m.group(3))

    t_first = next((seconds(l) for l in lines if re.search(r"\| Sample 0/", l)), None)
    t_done = next((seconds(l) for l in reversed(lines) if l.rstrip().endswith("| Finished")), None)
    return wall, cpu, t_first, t_done, lines


def load_rgb(path):
    img = bpy.data.images.load(os.path.abspath(path))
    img.colorspace_settings.name = "Non-Color"  # the float values as stored
    size, px = tuple(img.size), img.pixels[:]
    bpy.data.images.remove(img)
    return size, [px[i:i + 3] for i in range(0, len(px), 4)]


def compare(out, ref):
    """Relative RMSE sqrt(mean over pixels and channels of (x - r)^2 / (r^2 + f)) and ratio of the means;
    f = min(0.1, mean of r)^2, as core/image/ImageMetrics.h (relativeRmseFloor)."""
    (size, x), (rsize, r) = load_rgb(out), load_rgb(ref)
    if size != rsize:
        sys.exit(f"{ref}: {rsize[0]}x{rsize[1]}, not {size[0]}x{size[1]}")
    n = 3 * len(r)
    mean = sum(sum(p) for p in r) / n
    f = min(0.1, mean) ** 2 if mean > 0 else 0.01
    rel = math.sqrt(sum((a - b) ** 2 / (b * b + f) for pa, pb in zip(x, r) for a, b in zip(pa, pb)) / n)
    ratio = sum(sum(p) for p in x) / sum(sum(p) for p in r)
    print(f"cycles: against {ref}: relative RMSE {100 * rel:.3f} %, mean {ratio:.5f} x the reference's")
    noise = os.path.splitext(ref)[0] + ".noise" + os.path.splitext(ref)[1]
    if os.path.exists(noise):
        se = load_rgb(noise)[1]
        ref_rel = math.sqrt(sum(s * s / (b * b + f) for ps, pb in zip(se, r) for s, b in zip(ps, pb)) / n)
        own = math.sqrt(max(rel * rel - ref_rel * ref_rel, 0.0))
        print(f"cycles: the reference's own noise ({noise}) accounts for {100 * ref_rel:.3f} %; "
              f"Cycles' error alone is about {100 * own:.3f} %")


def serve(a, scene):
    """--serve: renders the jobs read from standard input in this process (no Blender start-up per image)."""
    print(f"@@cycles ready blender={bpy.app.version_string} threads={a.threads or 'auto'}", flush=True)
    for line in sys.stdin:
        t = line.split()
        if not t:
            continue
        if t[0] == "quit":
            break
        if t[0] != "render" or len(t) != 7:
            print(f"@@cycles error bad job: {line.strip()}", flush=True)
            continue
        out, spp, width, height, camera, seed = t[1], int(t[2]), int(t[3]), int(t[4]), t[5], int(t[6])
        place_camera(scene.camera, camera, a.scale, a.scene_vertices)
        scene.render.resolution_x, scene.render.resolution_y = width, height
        scene.cycles.samples = spp
        scene.cycles.seed = seed
        wall, cpu, t_first, t_done, _ = render_capturing_stats()
        path = t_done - t_first if t_first is not None and t_done is not None else -1.0
        t0 = time.perf_counter()
        bpy.data.images["Render Result"].save_render(filepath=os.path.abspath(out), scene=scene)
        save = time.perf_counter() - t0
        print(f"@@cycles done {out} wall={wall:.6f} cpu={cpu:.6f} path={path:.6f} save={save:.6f}", flush=True)


def main():
    t_start = time.perf_counter()
    a = parse_args()
    scene = build_scene(a)
    if a.serve:
        serve(a, scene)
        return
    print(f"cycles: Blender {bpy.app.version_string}, sampling pattern {scene.cycles.sampling_pattern}, "
          f"{a.width}x{a.height}, {a.spp} spp, max bounces {a.bounces}, threads "
          f"{a.threads or 'auto'}, setup {time.perf_counter() - t_start:.3f} s, load average {loadavg()}")
    paths = a.width * a.height * a.spp
    for k in range(a.repeat):
        la0 = loadavg()
        dt, cpu, t_first, t_done, lines = render_capturing_stats()
        if lines:
            print(f"cycles: last status line: {lines[-1].strip()}")
        print(f"cycles: render {k + 1}/{a.repeat}: wall {dt:.3f} s, {a.spp / dt:.2f} samples/s per pixel, "
              f"{paths / dt / 1e6:.4f} M paths/s (wall); CPU {cpu:.3f} s, {paths / cpu / 1e6:.4f} M paths per CPU "
              f"second; load average before {la0}, after {loadavg()}")
        if t_first is not None and t_done is not None and t_done > t_first:
            pt = t_done - t_first
            print(f"cycles: Cycles' own times: total {t_done:.2f} s, scene sync {t_first:.2f} s, path tracing "
                  f"{pt:.2f} s, {paths / pt / 1e6:.4f} M paths/s (path tracing)")
    t0 = time.perf_counter()
    bpy.data.images["Render Result"].save_render(filepath=os.path.abspath(a.out), scene=scene)
    print(f"cycles: wrote {a.out} in {time.perf_counter() - t0:.3f} s; script total "
          f"{time.perf_counter() - t_start:.3f} s")
    if a.reference:
        compare(a.out, a.reference)


main()
