#!/usr/bin/python3
"""VTK beside vxr on the scenes of `vxr bench peer --export-scenes`.

Draws each exported scene with VTK's volume mappers (the CPU fixed-point
ray caster and, where asked, the OpenGL GPU ray caster) at several sample
distances, times the frames, scores each image against vxr's CPU reference
exactly as `vxr bench peer` scores vxr's (RMSE in 8-bit units over RGBA over
black), and sets both speed-vs-error fronts side by side: for each VTK
setting, vxr's fastest step at least as accurate, and the speed ratio.

Run by ci/peer-vtk.sh (which installs python3-vtk9 and runs it under Xvfb):
  vtk_peer.py out/peer/peer.json [--distances 2 1 0.5] [--mappers fixed gpu]
Writes vtk-peer.json and vtk-peer.png (both fronts, time against error, with
VTK's own charts) beside the report.

The scene is matched to vxr's, not left at VTK's defaults:
- geometry: vxr samples voxel centres (i + 0.5) * voxel_size with clamp to
  the box edge; VTK's image data ends at the outer voxel centres. The volume
  is padded by one edge-replicated voxel a side and cropped to vxr's box, so
  both tools see the same function over the same box.
- opacity: vxr's extinction is density * ramp(value) per opacity unit
  distance; VTK's scalar opacity is an opacity per unit distance, so the
  ramp becomes 1 - exp(-density * ramp * unit) (tabulated), and both correct
  for the sample distance the same way. MIP: vxr shows colour * ramp(max)
  with opacity ramp(max), VTK's mapper its plain ramp.
- camera: the same eye, target, up and vertical field of view; VTK's rows
  are flipped to vxr's top-row-first order.

Checked by eye and by error: the fixed-point mapper's images converge on the
reference to RMSE 1.8 (MRI E-A), 4.0 (MRI MIP), 0.4 (vessels), the rest
spread along silhouettes (its 15-bit fixed point). The GPU mapper (Mesa's
OpenGL here) reaches 0.075 on the isotropic vessels but differs at the MRI's
top and bottom faces (anisotropic voxels 1x1x5 with cropping): its MRI errors
are not comparable, which is why it is not run by default.
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np
import vtk
from vtk.util import numpy_support

DTYPES = {"u8": np.uint8, "u16": np.uint16, "f32": np.float32}


def fail(msg):
    print(f"vtk_peer: {msg}", file=sys.stderr)
    sys.exit(1)


def load_volume(folder, scene):
    info = scene["volume"]
    path = os.path.join(folder, scene["files"]["volume"])
    nx, ny, nz = info["dims"]
    dtype = DTYPES.get(info["dtype"])
    if dtype is None:
        fail(f"{path}: dtype {info['dtype']} is not one this script reads (u8, u16, f32)")
    voxels = np.fromfile(path, dtype=np.dtype(dtype).newbyteorder("<"))
    if voxels.size != nx * ny * nz:
        fail(f"{path}: {voxels.size} voxels, the report says {nx}x{ny}x{nz}; export the scenes again")
    return voxels.reshape(nz, ny, nx)


def image_data(voxels, scene):
    """Padded, edge-replicated image data whose padded points sit at vxr's voxel centres."""
    vs = np.array(scene["volume"]["voxel_size"], dtype=float)
    centre = np.array(scene["volume"]["centre"], dtype=float)
    dims = np.array(scene["volume"]["dims"], dtype=float)
    lo = centre - 0.5 * dims * vs  # vxr's box
    padded = np.ascontiguousarray(np.pad(voxels, 1, mode="edge"))
    img = vtk.vtkImageData()
    img.SetDimensions(padded.shape[2], padded.shape[1], padded.shape[0])
    img.SetSpacing(*vs)
    img.SetOrigin(*(lo + 0.5 * vs - vs))  # padded point 1 is voxel 0's centre
    arr = numpy_support.numpy_to_vtk(padded.ravel(), deep=True)
    arr.SetName("voxels")
    img.GetPointData().SetScalars(arr)
    box = [lo[0], lo[0] + dims[0] * vs[0], lo[1], lo[1] + dims[1] * vs[1], lo[2], lo[2] + dims[2] * vs[2]]
    return img, box


def volume_property(scene):
    tf = scene["transfer"]
    lo, hi = tf["window"]
    if tf["colormap"] != "gray":
        fail(f"scene {scene['scene']}: colormap {tf['colormap']}: only gray is matched in VTK")
    points = tf["opacity_points"]
    ramp = lambda x: float(np.interp(x, [p[0] for p in points], [p[1] for p in points]))
    color = vtk.vtkColorTransferFunction()
    color.AddRGBPoint(lo, 0.0, 0.0, 0.0)
    color.AddRGBPoint(hi, 1.0, 1.0, 1.0)
    opacity = vtk.vtkPiecewiseFunction()
    unit = tf["opacity_unit_distance"]
    ea = tf["model"] == "ea"
    if ea and unit <= 0:
        fail(f"scene {scene['scene']}: opacity per voxel (unit distance 0) has no VTK counterpart; "
             "export with --opacity-unit-distance > 0")
    n = 256  # the tabulated ramp: its piecewise-linear error is far below 1/255
    for i in range(n + 1):
        x = i / n
        a = 1.0 - math.exp(-tf["density"] * ramp(x) * unit) if ea else ramp(x)
        opacity.AddPoint(lo + x * (hi - lo), a)
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(color)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(unit if ea else 1.0)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()
    return prop


def make_mapper(kind, scene, img, box, distance):
    if kind == "fixed":
        m = vtk.vtkFixedPointVolumeRayCastMapper()
        m.SetImageSampleDistance(1.0)
        m.SetAutoAdjustSampleDistances(0)
        m.SetSampleDistance(distance)
        m.SetInteractiveSampleDistance(distance)
    else:
        m = vtk.vtkGPUVolumeRayCastMapper()
        m.SetAutoAdjustSampleDistances(0)
        m.SetLockSampleDistanceToInputSpacing(0)
        m.SetUseJittering(0)
        m.SetSampleDistance(distance)
    m.SetInputData(img)
    m.SetCropping(1)
    m.SetCroppingRegionPlanes(*box)
    m.SetCroppingRegionFlagsToSubVolume()
    if scene["transfer"]["model"] == "mip":
        m.SetBlendModeToMaximumIntensity()
    elif scene["transfer"]["model"] == "ea":
        m.SetBlendModeToComposite()
    else:
        fail(f"scene {scene['scene']}: model {scene['transfer']['model']} is not matched in VTK")
    return m


def render_window():
    """One off-screen window for every frame: VTK on X closes the display with a window."""
    ren = vtk.vtkRenderer()
    ren.SetBackground(0, 0, 0)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetMultiSamples(0)
    win.AddRenderer(ren)
    return win, ren


def place_camera(win, ren, scene):
    cam_info = scene["camera"]
    win.SetSize(*cam_info["image_size"])
    cam = ren.GetActiveCamera()
    cam.SetPosition(*cam_info["eye"])
    cam.SetFocalPoint(*cam_info["target"])
    cam.SetViewUp(*cam_info["up"])
    cam.SetViewAngle(cam_info["fov_y_deg"])


def read_rgba_over_black(win, w, h):
    """The frame as 8-bit RGBA over black, top row first (vxr's order)."""
    data = vtk.vtkUnsignedCharArray()
    win.GetPixelData(0, 0, w - 1, h - 1, 0, data, 0)  # back buffer, where the frame was drawn
    rgb = numpy_support.vtk_to_numpy(data).reshape(h, w, 3)[::-1]
    rgba = np.full((h, w, 4), 255, dtype=np.uint8)
    rgba[..., :3] = rgb
    return rgba


def rmse(a, b):
    d = a.astype(np.float64) - b.astype(np.float64)
    return float(np.sqrt(np.mean(d * d)))


def time_frames(win, repeats):
    """Median wall ms of one frame drawn and read back (as vxr's frames are timed)."""
    w, h = win.GetSize()
    data = vtk.vtkUnsignedCharArray()
    win.Render()  # warm-up: table builds, shader compiles
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        win.Render()
        win.GetPixelData(0, 0, w - 1, h - 1, 0, data, 0)
        times.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(times))


def vxr_front(scene):
    """vxr's (step, wall ms, rmse) with skipping on, from the peer report."""
    return [(r["step_voxels"], r["on"]["wall_ms"], r["rmse_vs_reference"]) for r in scene["steps"]]


def fastest_within(front, err):
    ok = [p for p in front if p[2] <= err]
    return min(ok, key=lambda p: p[1]) if ok else None


# Colours per scene (vxr's line, VTK's points in the same hue, lighter per mapper).
SCENE_COLOURS = [(31, 119, 180), (214, 39, 40), (44, 160, 44), (148, 103, 189)]


def plot_fronts(path, doc):
    """Each scene's vxr front (skipping on) as a line and VTK's points, wall ms
    against RMSE on log axes: the PNG beside the JSON report."""
    view = vtk.vtkContextView()
    view.GetRenderWindow().SetOffScreenRendering(1)
    view.GetRenderWindow().SetSize(900, 620)
    view.GetRenderer().SetBackground(1, 1, 1)
    chart = vtk.vtkChartXY()
    view.GetScene().AddItem(chart)
    chart.SetTitle("vxr beside VTK: time against error (lower left is better)")
    chart.SetShowLegend(True)

    def add(label, points, colour, line):
        table = vtk.vtkTable()
        xs, ys = vtk.vtkFloatArray(), vtk.vtkFloatArray()
        xs.SetName("wall ms")
        ys.SetName(label)
        for x, y in points:  # in the report's order: vxr's line runs along its steps
            xs.InsertNextValue(x)
            ys.InsertNextValue(y)
        table.AddColumn(xs)
        table.AddColumn(ys)
        plot = chart.AddPlot(vtk.vtkChart.LINE if line else vtk.vtkChart.POINTS)
        plot.SetInputData(table, 0, 1)
        plot.SetColor(*colour, 255)
        plot.SetWidth(2.0)

    for i, scene in enumerate(doc["scenes"]):
        c = SCENE_COLOURS[i % len(SCENE_COLOURS)]
        # Log axes: a point at RMSE 0 (an exact match) cannot be drawn.
        add(f"{scene['scene']}: vxr", [(p["wall_ms"], p["rmse_vs_reference"]) for p in scene["vxr"]
                                       if p["rmse_vs_reference"] > 0], c, True)
        for k, kind in enumerate(sorted({r["mapper"] for r in scene["vtk"]})):
            light = tuple(int(v + (255 - v) * (0.35 + 0.25 * k)) for v in c)
            add(f"{scene['scene']}: VTK {kind}", [(r["wall_ms"], r["rmse_vs_reference"]) for r in scene["vtk"]
                                                  if r["mapper"] == kind and r["rmse_vs_reference"] > 0], light, False)
    for axis, title in ((vtk.vtkAxis.BOTTOM, "wall ms per frame"), (vtk.vtkAxis.LEFT, "RMSE vs the CPU reference (8-bit units)")):
        chart.GetAxis(axis).SetLogScale(True)
        chart.GetAxis(axis).SetTitle(title)
    view.GetRenderWindow().Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(view.GetRenderWindow())
    grab.Update()
    tmp = path + ".tmp.png"
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(tmp)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
    if writer.GetErrorCode():
        fail(f"{path}: cannot write the plot (VTK error {writer.GetErrorCode()})")
    os.replace(tmp, path)  # never a half-written plot


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("report", help="peer.json written by `vxr bench peer --export-scenes`")
    ap.add_argument("--distances", type=float, nargs="+", default=[4.0, 2.0, 1.0, 0.5, 0.25],
                    help="VTK sample distances in world units (VTK's default is 1)")
    ap.add_argument("--mappers", nargs="+", default=["fixed"], choices=["fixed", "gpu"],
                    help="fixed: vtkFixedPointVolumeRayCastMapper (CPU); gpu: vtkGPUVolumeRayCastMapper (OpenGL)")
    ap.add_argument("--repeats", type=int, default=3, help="timed frames per point; the median is kept")
    ap.add_argument("--out", help="JSON report (default: vtk-peer.json beside the peer report)")
    ap.add_argument("--save-images", action="store_true", help="write each VTK frame as .rgba beside the report")
    a = ap.parse_args()

    try:
        with open(a.report) as f:
            report = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{a.report}: cannot read the peer report ({e}); run `vxr bench peer --export-scenes` first")
    folder = os.path.dirname(os.path.abspath(a.report))
    out_path = a.out or os.path.join(folder, "vtk-peer.json")
    if os.path.abspath(out_path) == os.path.abspath(a.report):
        fail(f"{out_path}: the output is the input report; name another --out")
    scenes = report.get("scenes", [])
    if not scenes or any("files" not in s for s in scenes):
        fail(f"{a.report}: no exported scenes; run `vxr bench peer --export-scenes`")

    threads = vtk.vtkMultiThreader.GetGlobalDefaultNumberOfThreads()
    print(f"VTK {vtk.vtkVersion.GetVTKVersion()}, {threads} threads; vxr: {report['machine'].get('device', '?')}")
    doc = {"vtk_version": vtk.vtkVersion.GetVTKVersion(), "vtk_threads": threads, "peer_report": a.report,
           "units": {"time": "median wall ms of one frame drawn and read back (512x512 RGB)",
                     "error": "RMSE in 8-bit units over RGBA over black against vxr's CPU reference"},
           "scenes": []}
    total = len(scenes) * len(a.mappers) * len(a.distances)
    done = 0
    t_start = time.perf_counter()
    win, ren = render_window()
    for scene in scenes:
        w, h = scene["camera"]["image_size"]
        place_camera(win, ren, scene)
        voxels = load_volume(folder, scene)
        ref_path = os.path.join(folder, scene["files"]["reference_rgba"])
        ref = np.fromfile(ref_path, dtype=np.uint8)
        if ref.size != w * h * 4:
            fail(f"{ref_path}: {ref.size} bytes, expected {w}x{h} RGBA; export the scenes again")
        ref = ref.reshape(h, w, 4)
        img, box = image_data(voxels, scene)
        prop = volume_property(scene)
        front = vxr_front(scene)
        rows = []
        for kind in a.mappers:
            for d in a.distances:
                vol = vtk.vtkVolume()
                vol.SetMapper(make_mapper(kind, scene, img, box, d))
                vol.SetProperty(prop)
                ren.AddVolume(vol)
                ren.ResetCameraClippingRange()
                ms = time_frames(win, a.repeats)
                frame = read_rgba_over_black(win, w, h)
                err = rmse(frame, ref)
                if a.save_images:
                    slug = scene["files"]["volume"][:-4]
                    frame.tofile(os.path.join(folder, f"{slug}-vtk-{kind}-{d:g}.rgba"))
                best = fastest_within(front, err)
                row = {"mapper": kind, "sample_distance": d, "wall_ms": ms, "rmse_vs_reference": err,
                       "vxr_fastest_at_least_as_accurate": None if best is None else
                       {"step_voxels": best[0], "wall_ms": best[1], "rmse_vs_reference": best[2],
                        "vtk_ms_over_vxr_ms": ms / best[1]}}
                rows.append(row)
                vs = (f"vxr step {best[0]:g}: {best[1]:8.2f} ms rmse {best[2]:6.3f}  vxr {ms / best[1]:5.2f}x faster"
                      if best else "no vxr step as accurate")
                print(f"{scene['scene']:<18} vtk {kind:<5} d {d:<5g} {ms:9.2f} ms rmse {err:7.3f}  | {vs}")
                done += 1
                el = time.perf_counter() - t_start
                print(f"vtk_peer: {done}/{total} frames' settings, {el:.0f} s, ETA {el / done * (total - done):.0f} s",
                      file=sys.stderr)
                ren.RemoveVolume(vol)
        doc["scenes"].append({"scene": scene["scene"], "vtk": rows,
                              "vxr": [{"step_voxels": s, "wall_ms": t, "rmse_vs_reference": e} for s, t, e in front]})
    plot_path = os.path.splitext(out_path)[0] + ".png"
    plot_fronts(plot_path, doc)
    doc["plot"] = plot_path
    tmp = out_path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(doc, f, indent=2)
    os.replace(tmp, out_path)  # never a half-written report
    print(plot_path)
    print(out_path)


if __name__ == "__main__":
    main()
