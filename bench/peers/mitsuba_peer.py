#!/usr/bin/env python3
"""Mitsuba 3 as a side-by-side peer of lightgraph: on Mitsuba's own Cornell box, or on a
scene lightgraph exported (`lightgraph export --format mitsuba`, e.g. Sponza).

Self-contained: Python 3.12 + numpy + mitsuba 3.9.1 + drjit 1.5.0 (see bench/peers/README.md).

  render   render mi.cornell_box() (box pixel filter, path integrator, max_depth 8, rr_depth 5),
           or with --scene-xml an exported scene as its XML says (film, integrator), in passes
           of --spp-per-pass samples per pixel until --seconds of timed rendering have
           accumulated; write the average as a float32 RGB EXR; print one JSON line.
  rmse     RMSE and relative MSE of one or more EXRs against a reference EXR (JSON lines and a
           Markdown table).
  summary  the Markdown summary of a whole comparison run (used by run_gpu.sh).

Examples:
  python3 bench/peers/mitsuba_peer.py render --mode megakernel --res 1280x720 \\
      --spp-per-pass 16 --seconds 10 --out /tmp/mi.exr
  python3 bench/peers/mitsuba_peer.py render --scene-xml /tmp/sponza/scene.xml --res 1280x720 \\
      --seconds 10 --out /tmp/mi-sponza.exr
  python3 bench/peers/mitsuba_peer.py rmse --reference ref.exr --image mitsuba=/tmp/mi.exr
"""
import argparse
import json
import math
import os
import re
import sys
import time

MITSUBA_VERSION = '3.9.1'
DRJIT_VERSION = '1.5.0'

# Mitsuba's cornell box as resolved in shared/scenes/builtin-cornell/mitsuba-cornell-box.txt
# (mitsuba 3.9.1); the script refuses to compare if mi.cornell_box() ever differs from it.
CAMERA_ORIGIN = (0.0, 0.0, 3.9)
CAMERA_FOV = 39.3077  # degrees, on the smaller image axis
CAMERA_TO_WORLD = ((-1, 0, 0, 0), (0, 1, 0, 0), (0, 0, -1, 3.9), (0, 0, 0, 1))
REFLECTANCE = {
    'white': (0.885809, 0.698859, 0.666422),
    'green': (0.105421, 0.37798, 0.076425),
    'red': (0.570068, 0.0430135, 0.0443706),
}
RADIANCE = (18.387, 13.9873, 6.75357)
EMITTER_THRESHOLD = 1.0  # reference radiance (max channel) above which a pixel counts as the light's
MAX_DEPTH = 8  # Mitsuba semantics: at most 8 path segments
RR_DEPTH = 5


def fail(msg):
    sys.exit(f'mitsuba_peer.py: error: {msg}')


def log(msg):
    print(f'[mitsuba_peer] {msg}', file=sys.stderr, flush=True)


def installed_variants(mi):
    """The variants whose modules are installed. mi.variants() lists those the build was made
    with, also when a slimmed wheel (prepare_wheels.sh) left some out."""
    import importlib.util
    out = []
    for v in mi.variants():
        try:
            if importlib.util.find_spec(f'mitsuba.{v}') is not None:
                out.append(v)
        except Exception:
            pass
    return out


def import_mitsuba(variant, for_render=True):
    """Imports mitsuba and drjit and sets `variant`, or exits with a message that says why."""
    try:
        import numpy  # noqa: F401
    except ImportError:
        fail('numpy is not importable: install it (python3 -m pip install numpy)')
    try:
        import drjit as dr
        import mitsuba as mi
    except ImportError as e:
        fail(f'cannot import mitsuba/drjit ({e}). Install the wheels first, e.g. on the GPU machine:\n'
             '  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade '
             '--target /tmp/site .whl/*.whl && export PYTHONPATH=/tmp/site\n'
             '(.whl/ is made by bench/peers/prepare_wheels.sh), or anywhere with network access:\n'
             f'  python3 -m pip install mitsuba=={MITSUBA_VERSION} drjit=={DRJIT_VERSION}')
    if getattr(mi, '__version__', None) != MITSUBA_VERSION or getattr(dr, '__version__', None) != DRJIT_VERSION:
        log(f'warning: mitsuba {getattr(mi, "__version__", "?")} / drjit {getattr(dr, "__version__", "?")}; '
            f'the comparison was set up with mitsuba {MITSUBA_VERSION} / drjit {DRJIT_VERSION}')
    available = installed_variants(mi)
    if variant not in available:
        fail(f"variant '{variant}' is not available in this mitsuba installation; available: {available} "
             f"(mi.variants() = {list(mi.variants())})")
    try:
        mi.set_variant(variant)
    except Exception as e:  # e.g. no CUDA driver / OptiX, LLVM too old
        hint = ''
        if variant.startswith('cuda'):
            hint = ' (the cuda variants need an NVIDIA driver with libcuda.so and libnvoptix.so.1)'
        elif variant.startswith('llvm'):
            hint = ' (the llvm variants need libLLVM >= 17; point DRJIT_LIBLLVM_PATH at one)'
        fail(f"cannot set variant '{variant}': {e}{hint}; available variants: {available}")
    if for_render and variant.startswith('llvm'):
        try:
            llvm = tuple(dr.detail.llvm_version())
        except Exception:
            llvm = None
        if llvm is not None and llvm < (17,):
            fail(f"variant '{variant}' found libLLVM {'.'.join(map(str, llvm))}, but needs >= 17 (older "
                 "ones abort with 'Cannot select: fminimum'); point DRJIT_LIBLLVM_PATH at a newer libLLVM")
    return mi, dr


def parse_res(s):
    m = re.fullmatch(r'(\d+)[xX](\d+)', s)
    if not m or int(m.group(1)) == 0 or int(m.group(2)) == 0:
        raise argparse.ArgumentTypeError(f"'{s}' is not WxH")
    return int(m.group(1)), int(m.group(2))


def scalar(x):
    """First element of a Dr.Jit value of any variant (scalar or JIT array of width 1) as a float."""
    import numpy as np
    return float(np.asarray(x).reshape(-1)[0])


# ----------------------------------------------------------------------------------------------
# render

def scene_dict(mi, width, height, spp):
    d = mi.cornell_box()
    sensor = d['sensor']
    # The camera must be the one in mitsuba-cornell-box.txt (and scenes/cornell/cornell-mitsuba.ron).
    problems = []
    if sensor.get('type') != 'perspective':
        problems.append(f"sensor type {sensor.get('type')!r}, expected 'perspective'")
    if abs(float(sensor.get('fov', float('nan'))) - CAMERA_FOV) > 1e-4:
        problems.append(f"fov {sensor.get('fov')!r}, expected {CAMERA_FOV}")
    if sensor.get('fov_axis', 'x') != 'smaller':
        problems.append(f"fov_axis {sensor.get('fov_axis')!r}, expected 'smaller'")
    import numpy as np
    m = np.array(sensor['to_world'].matrix, dtype=np.float64).reshape(4, 4)
    if not np.allclose(m, np.array(CAMERA_TO_WORLD, dtype=np.float64), atol=1e-5):
        problems.append(f'to_world {m.tolist()}, expected look_at (0,0,3.9) -> (0,0,0), up +y = {CAMERA_TO_WORLD}')
    for name, rgb in REFLECTANCE.items():
        got = d.get(name, {}).get('reflectance', {}).get('value')
        if got is None or not np.allclose(got, rgb, atol=1e-6):
            problems.append(f'{name} reflectance {got!r}, expected {rgb}')
    got = d.get('light', {}).get('emitter', {}).get('radiance', {}).get('value')
    if got is None or not np.allclose(got, RADIANCE, atol=1e-4):
        problems.append(f'light radiance {got!r}, expected {RADIANCE}')
    if problems:
        fail('mi.cornell_box() differs from shared/scenes/builtin-cornell/mitsuba-cornell-box.txt: '
             + '; '.join(problems))

    sensor['fov_axis'] = 'smaller'  # explicit: the fov is on the smaller axis, as in lightgraph's scene
    sensor['film'] = {
        'type': 'hdrfilm',
        'width': width,
        'height': height,
        'rfilter': {'type': 'box'},  # the default of mi.cornell_box() is a Gaussian
        'pixel_format': 'rgb',
        'component_format': 'float32',
    }
    sensor['sampler'] = {'type': 'independent', 'sample_count': spp}
    d['integrator'] = {'type': 'path', 'max_depth': MAX_DEPTH, 'rr_depth': RR_DEPTH, 'hide_emitters': False}
    return d


def check_camera_rays(mi, scene, width, height):
    """Traces the film corners and centre through Mitsuba's sensor and compares the rays with
    direction(u, v) = normalize([(2u-1) tx, (1-2v) ty, -1]) from mitsuba-cornell-box.txt
    (ty = tan(fov/2) on the smaller axis; here generalised to any aspect ratio)."""
    import numpy as np
    sensor = scene.sensors()[0]
    t = math.tan(math.radians(CAMERA_FOV) / 2)
    aspect = width / height
    tx, ty = (t * aspect, t) if width >= height else (t, t / aspect)
    worst = 0.0
    for u, v in ((0.5, 0.5), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.25, 0.75)):
        ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(u, v), mi.Point2f(0.5, 0.5))
        d = np.array([scalar(ray.d.x), scalar(ray.d.y), scalar(ray.d.z)])
        o = np.array([scalar(ray.o.x), scalar(ray.o.y), scalar(ray.o.z)])
        e = np.array([(2 * u - 1) * tx, (1 - 2 * v) * ty, -1.0])
        e /= np.linalg.norm(e)
        worst = max(worst, float(np.abs(d - e).max()))
        if np.abs(d - e).max() > 1e-4 or np.abs(o - np.array(CAMERA_ORIGIN)).max() > 2e-3:
            fail(f'camera ray at film (u,v)=({u},{v}) is o={o.tolist()} d={d.tolist()}; expected '
                 f'o~{list(CAMERA_ORIGIN)} d={e.tolist()} (fov {CAMERA_FOV} on the smaller axis)')
    return worst


def load_exported(mi, path, width, height):
    """A scene `lightgraph export --format mitsuba` wrote, whose film must be `width` x `height`
    (export it with --res); returns the scene and its integrator's max_depth and rr_depth."""
    import xml.etree.ElementTree as ET
    if not os.path.isfile(path):
        fail(f'no such file: {path} (write it with: lightgraph export --format mitsuba --res WxH --out DIR)')
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        fail(f'{path}: {e}')
    integrator = root.find('integrator')
    if integrator is None or integrator.get('type') != 'path':
        fail(f'{path}: expected a <integrator type="path">, as lightgraph export writes')
    settings = {c.get('name'): int(c.get('value')) for c in integrator if c.tag == 'integer'}
    try:
        scene = mi.load_file(path)
    except Exception as e:
        fail(f'{path}: mitsuba cannot load it: {e}')
    size = tuple(int(v) for v in scene.sensors()[0].film().size())
    if size != (width, height):
        fail(f'{path}: its film is {size[0]}x{size[1]}, not --res {width}x{height}: export it with --res {width}x{height}')
    return scene, {k: settings.get(k) for k in ('max_depth', 'rr_depth')}


def cmd_render(a):
    width, height = a.res
    if a.spp_per_pass < 1:
        fail('--spp-per-pass must be at least 1')
    if a.seconds <= 0 and a.passes is None:
        fail('give --seconds > 0 or --passes')
    mi, dr = import_mitsuba(a.variant)
    import numpy as np
    jit = not a.variant.startswith('scalar')
    if a.mode == 'wavefront':
        if not jit:
            fail('--mode wavefront needs a JIT variant (cuda_* or llvm_*); the scalar variants have no such switch')
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)  # evaluated loops: one kernel per bounce
    elif jit:
        dr.set_flag(dr.JitFlag.SymbolicLoops, True)  # Mitsuba's default: a megakernel

    t0 = time.perf_counter()
    if a.scene_xml:
        scene, settings = load_exported(mi, a.scene_xml, width, height)
        load_s = time.perf_counter() - t0
        log(f'{a.variant} {a.mode}: {a.scene_xml} loaded in {load_s:.2f} s; integrator {settings}')
    else:
        scene = mi.load_dict(scene_dict(mi, width, height, a.spp_per_pass))
        settings = {'max_depth': MAX_DEPTH, 'rr_depth': RR_DEPTH}
        load_s = time.perf_counter() - t0
        ray_err = check_camera_rays(mi, scene, width, height)
        log(f'{a.variant} {a.mode}: scene loaded in {load_s:.2f} s; camera rays match the resolved '
            f'parameters (max direction error {ray_err:.1e})')

    def seed_of(k):
        # An opaque seed, so that no seed value is baked into the kernel (mitsuba 3.9 already
        # does this for a Python int; the probe pass below checks that a new seed compiles nothing).
        s = a.seed + k
        return dr.opaque(mi.UInt32, s) if jit else s

    def render(k):
        img = mi.render(scene, spp=a.spp_per_pass, seed=seed_of(k))
        if jit:
            dr.eval(img)
            dr.sync_thread()
        return img

    # Warm-up: Dr.Jit compiles one kernel (set) per distinct spp. Then one untimed probe pass with
    # a new seed, with the kernel history on, to check that a new seed compiles nothing.
    t0 = time.perf_counter()
    render(-2)
    warm_s = time.perf_counter() - t0
    probe = {}
    if jit:
        dr.kernel_history_clear()
        with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
            t0 = time.perf_counter()
            render(-1)
            probe_s = time.perf_counter() - t0
            hist = dr.kernel_history()
        jit_kernels = [h for h in hist if h.get('type') == dr.KernelType.JIT]
        compiled = [h for h in jit_kernels if not h.get('cache_hit', True)]
        kernel_ms = sum(float(h.get('execution_time', 0.0)) for h in hist)
        # wall time of a pass against the time its kernels ran: the difference is host overhead
        # (tracing the program in Python/C++, launches), which larger passes amortise
        probe = {'launches_per_pass': len(jit_kernels), 'compiled_in_probe': len(compiled),
                 'probe_seconds': round(probe_s, 4), 'probe_kernel_seconds': round(kernel_ms / 1e3, 4)}
        if compiled:
            log(f'warning: a pass with a new seed compiled {len(compiled)} kernel(s): timed passes '
                'include compilation')
    log(f'warm-up pass {warm_s:.2f} s; {probe}')

    acc = None
    timed = 0.0
    passes = 0
    while True:
        if a.passes is not None and passes >= a.passes:
            break
        if a.passes is None and timed >= a.seconds:
            break
        t0 = time.perf_counter()
        img = render(passes)
        timed += time.perf_counter() - t0
        passes += 1
        # Accumulate outside the timed window (and evaluate it there, so that the addition is not
        # fused into the next timed render).
        acc = img if acc is None else acc + img
        if jit:
            dr.eval(acc)
            dr.sync_thread()

    mean = np.array(acc, dtype=np.float32).reshape(height, width, -1)[:, :, :3] / passes
    spp = passes * a.spp_per_pass
    if a.out:
        os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
        bmp = mi.Bitmap(np.ascontiguousarray(mean, dtype=np.float32), mi.Bitmap.PixelFormat.RGB)
        bmp.write(a.out)
    finite = bool(np.isfinite(mean).all())
    result = {
        'peer': f'mitsuba {mi.__version__} (drjit {dr.__version__})',
        'variant': a.variant,
        'mode': a.mode,
        'width': width,
        'height': height,
        'spp': spp,
        'spp_per_pass': a.spp_per_pass,
        'passes': passes,
        'seconds': round(timed, 4),
        'samples_per_second': width * height * spp / timed if timed > 0 else None,
        'warmup_seconds': round(warm_s, 3),
        'scene_load_seconds': round(load_s, 3),
        'mean_rgb': [round(float(x), 6) for x in mean.reshape(-1, 3).mean(axis=0)],
        'finite': finite,
        'out': a.out,
        'scene': a.scene_xml or 'mi.cornell_box()',
        **settings,
        **probe,
    }
    if not finite:
        log('warning: the image has NaN or infinite pixels')
    print(json.dumps(result), flush=True)


# ----------------------------------------------------------------------------------------------
# rmse

def load_rgb(mi, path):
    """An EXR as an (H, W, 3) float32 array: R, G, B channels (any layer prefix), alpha dropped,
    top row first (Mitsuba's and lightgraph's convention)."""
    import numpy as np
    if not os.path.isfile(path):
        fail(f'no such file: {path}')
    try:
        bmp = mi.Bitmap(path)
    except Exception as e:
        fail(f'cannot read {path}: {e}')
    names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
    arr = np.array(bmp)
    if arr.ndim == 2:
        arr = arr[:, :, None]
    arr = arr.astype(np.float32)
    short = [n.rsplit('.', 1)[-1].upper() for n in names]
    if all(c in short for c in 'RGB'):
        idx = [short.index(c) for c in 'RGB']
    elif len(names) >= 3:
        log(f'warning: {path} has channels {names}; taking the first three as R, G, B')
        idx = [0, 1, 2]
    else:
        fail(f'{path} has channels {names}: not an RGB image')
    return np.ascontiguousarray(arr[:, :, idx]), bmp.metadata()


def metadata_value(meta, key):
    try:
        return meta[key] if key in meta else None
    except Exception:
        return None


def image_metrics(x, ref, emitter_threshold=EMITTER_THRESHOLD):
    import numpy as np
    x64, r64 = x.astype(np.float64), ref.astype(np.float64)
    d2 = (x64 - r64) ** 2
    finite = np.isfinite(d2)
    d2 = np.where(finite, d2, 0.0)
    ref_mean = r64.reshape(-1, 3).mean(axis=0)
    # Pixels that see the light (radiance ~18; lit walls stay under ~1): with a box filter its
    # edge pixels vary between 0 and 18 from sample to sample and can dominate the RMSE.
    emitter = r64.max(axis=-1) >= emitter_threshold
    rest = d2[~emitter]
    return {
        'rmse': float(math.sqrt(d2.mean())),
        'rmse_excl_emitter': float(math.sqrt(rest.mean())) if rest.size else None,
        'emitter_pixels': int(emitter.sum()),
        'emitter_share_of_squared_error': float(d2[emitter].sum() / d2.sum()) if d2.sum() > 0 else 0.0,
        'relmse': float((d2 / (r64 ** 2 + 1e-2)).mean()),
        'mean_rgb': [round(float(v), 6) for v in x64.reshape(-1, 3).mean(axis=0)],
        # systematic difference from the reference (differing renderers show up here first)
        'mean_rel_diff_rgb': [round(float(v), 5) for v in x64.reshape(-1, 3).mean(axis=0) / ref_mean - 1],
        'nonfinite_values': int((~finite).sum()),
    }


def cmd_rmse(a):
    mi, _ = import_mitsuba(a.variant, for_render=False)
    ref, ref_meta = load_rgb(mi, a.reference)
    rows = []
    for spec in a.image:
        if '=' not in spec:
            fail(f"--image {spec}: expected NAME=PATH.exr")
        name, path = spec.split('=', 1)
        x, meta = load_rgb(mi, path)
        if x.shape != ref.shape:
            fail(f'{path} is {x.shape[1]}x{x.shape[0]} but the reference {a.reference} is '
                 f'{ref.shape[1]}x{ref.shape[0]}')
        row = {'image': name, 'path': path, 'reference': a.reference,
               **image_metrics(x, ref, a.emitter_threshold)}
        spp = metadata_value(meta, 'lightgraph.samples_per_pixel')
        if spp is not None:
            row['lightgraph_spp'] = int(spp)
        rows.append(row)
        print(json.dumps(row), flush=True)
    ref_spp = metadata_value(ref_meta, 'lightgraph.samples_per_pixel')
    out = ['', f'Against `{a.reference}`' + (f' ({ref_spp} spp)' if ref_spp else '') + ':', '',
           '| image | RMSE | RMSE without light pixels | relMSE | mean rel. diff (R, G, B) |',
           '|---|---|---|---|---|']
    for r in rows:
        diff = ', '.join(f'{100 * v:+.2f}%' for v in r['mean_rel_diff_rgb'])
        out.append(f"| {r['image']} | {r['rmse']:.5f} | {fmt(r.get('rmse_excl_emitter'), '.5f')} | "
                   f"{r['relmse']:.3e} | {diff} |")
    if rows and rows[0]['emitter_pixels']:
        out.append(f"\n{rows[0]['emitter_pixels']} pixels see the light (reference >= {a.emitter_threshold}); "
                   'their share of the squared error: '
                   + ', '.join(f"{r['image']} {100 * r['emitter_share_of_squared_error']:.0f}%" for r in rows))
    print('\n'.join(out), flush=True)


# ----------------------------------------------------------------------------------------------
# summary (no mitsuba needed)

LG_LINE = re.compile(r'(\d+) frames, (\d+) spp in ([\d.]+) s: ([\d.]+) ([kMG]?)samples/s')


def read_jsonl(path):
    rows = []
    if path and os.path.isfile(path):
        with open(path) as f:
            for line in f:
                line = line.strip()
                if line.startswith('{'):
                    try:
                        rows.append(json.loads(line))
                    except json.JSONDecodeError:
                        pass
    return rows


def last_lightgraph_line(path):
    """The match of lightgraph render's last summary line (LG_LINE) in the log at `path`, or None."""
    found = None
    if path and os.path.isfile(path):
        with open(path, errors='replace') as f:
            for line in f:
                found = LG_LINE.search(line) or found
    return found


def fmt(v, spec):
    return '–' if v is None else format(v, spec)


def cmd_summary(a):
    width, height = a.res
    entries = {}  # name -> {samples_per_second, seconds, spp}
    lg = None
    m = last_lightgraph_line(a.lightgraph_log)
    if m:
        frames, spp, secs = int(m.group(1)), int(m.group(2)), float(m.group(3))
        lg = {'frames': frames, 'spp': spp, 'seconds': secs,
              'samples_per_second': width * height * spp / secs, 'line': m.string.strip()}
    if lg:
        entries['lightgraph'] = lg
    for path in a.mitsuba_json:
        for r in read_jsonl(path):
            if 'samples_per_second' in r:
                entries[f"mitsuba-{r['mode']}"] = r
    rmse = {r['image']: r for r in read_jsonl(a.rmse_json)}

    title = a.title or 'lightgraph vs Mitsuba 3 on cornell-mitsuba'
    md = [f'# {title}', '']
    if a.device:
        md += [f'Device: {a.device}', '']
    md += [f'{width}x{height}, max depth {a.max_depth} (segments), Russian roulette from depth {a.rr_depth}, '
           f'box pixel filter; lightgraph layout `{a.layout}`; equal time {a.seconds:g} s.', '']
    ref_spp = None
    m = last_lightgraph_line(a.reference_log)
    if m:
        ref_spp = int(m.group(2))
        md += [f'Reference: lightgraph `{a.layout}`, {ref_spp} spp in {float(m.group(3)):.0f} s '
               '(its own seed, independent of the equal-time runs).', '']
    md += ['| renderer | spp | seconds | Msamples/s | lightgraph / this | RMSE | RMSE at exactly '
           f'{a.seconds:g} s | RMSE w/o light pixels | relMSE | mean rel. diff vs reference (R, G, B) |',
           '|---|---|---|---|---|---|---|---|---|---|']
    lg_sps = entries.get('lightgraph', {}).get('samples_per_second')
    result = {'width': width, 'height': height, 'layout': a.layout, 'seconds': a.seconds,
              'device': a.device, 'reference_spp': ref_spp, 'runs': {}}
    for name in ('lightgraph', 'mitsuba-megakernel', 'mitsuba-wavefront'):
        e = entries.get(name)
        r = rmse.get(name)
        if e is None and r is None:
            md.append(f'| {name} | – | – | – | – | – | – | – | – | failed or not run |')
            continue
        sps = e.get('samples_per_second') if e else None
        secs = e.get('seconds') if e else None
        ratio = f'{lg_sps / sps:.2f}x' if (lg_sps and sps) else '–'
        if name == 'lightgraph':
            ratio = '1.00x' if lg_sps else '–'
        # MSE ~ 1/time for an unbiased estimator: scale to exactly the nominal time.
        scaled = r['rmse'] * math.sqrt(secs / a.seconds) if (r and secs) else None
        diff = ', '.join(f'{100 * v:+.2f}%' for v in r['mean_rel_diff_rgb']) if r else '–'
        md.append('| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |'.format(
            name, e.get('spp', '–') if e else '–', f'{secs:.2f}' if secs else '–',
            f'{sps / 1e6:.1f}' if sps else '–', ratio,
            f"{r['rmse']:.5f}" if r else '–', f'{scaled:.5f}' if scaled else '–',
            fmt(r.get('rmse_excl_emitter') if r else None, '.5f'),
            f"{r['relmse']:.3e}" if r else '–', diff))
        result['runs'][name] = {
            'samples_per_second': sps, 'seconds': secs, 'spp': e.get('spp') if e else None,
            'lightgraph_over_this': (lg_sps / sps) if (lg_sps and sps) else None,
            'rmse': r['rmse'] if r else None, 'rmse_at_nominal_time': scaled,
            'rmse_excl_emitter': r.get('rmse_excl_emitter') if r else None,
            'emitter_share_of_squared_error': r.get('emitter_share_of_squared_error') if r else None,
            'relmse': r['relmse'] if r else None,
            'mean_rel_diff_rgb': r['mean_rel_diff_rgb'] if r else None,
            **({k: e[k] for k in ('launches_per_pass', 'compiled_in_probe', 'warmup_seconds',
                                  'probe_seconds', 'probe_kernel_seconds', 'spp_per_pass') if k in e}
               if e else {}),
        }
    notes = ['"lightgraph / this" is the ratio of samples/s; "RMSE at exactly T s" scales each RMSE by '
             'sqrt(its seconds / T) (MSE ~ 1/time), so that runs that stopped a little late compare fairly.']
    lg_run = result['runs'].get('lightgraph', {})
    for name in ('mitsuba-megakernel', 'mitsuba-wavefront'):
        m_run = result['runs'].get(name, {})
        if lg_run.get('rmse_at_nominal_time') and m_run.get('rmse_at_nominal_time'):
            ratio = (m_run['rmse_at_nominal_time'] / lg_run['rmse_at_nominal_time']) ** 2
            extra = ''
            if lg_run.get('rmse_excl_emitter') and m_run.get('rmse_excl_emitter'):
                r2 = (m_run['rmse_excl_emitter'] ** 2 * m_run['seconds']) / (
                    lg_run['rmse_excl_emitter'] ** 2 * lg_run['seconds'])
                extra = f' (without the light\'s pixels: {r2:.2f}x)'
            notes.append(f'{name}: MSE {ratio:.2f}x lightgraph\'s at equal time{extra}, i.e. it needs '
                         f'about that many times lightgraph\'s time for the same error.')
    if ref_spp and lg_run.get('spp'):
        notes.append(f'The reference has {ref_spp} spp and the equal-time lightgraph run {lg_run["spp"]}: '
                     f'the reference\'s own noise adds about {100 * lg_run["spp"] / ref_spp:.0f}% of '
                     'lightgraph\'s equal-time variance to every MSE above.')
    shares = [f"{n} {100 * r['emitter_share_of_squared_error']:.0f}%" for n, r in rmse.items()
              if r.get('emitter_share_of_squared_error') is not None and r.get('emitter_pixels')]
    if shares:
        first = next(iter(rmse.values()))
        notes.append(f"{first.get('emitter_pixels')} pixels see the light (reference >= {EMITTER_THRESHOLD}); "
                     'with a box filter its edge pixels flip between 0 and ~18 from sample to sample, so '
                     'they carry a large share of the squared error: ' + ', '.join(shares)
                     + '. "RMSE w/o light pixels" leaves them out.')
    notes.append('"mean rel. diff" shows a systematic difference between a renderer and the reference; '
                 'lightgraph\'s own row shows how far noise alone moves it.')
    for name in ('mitsuba-megakernel', 'mitsuba-wavefront'):
        e = entries.get(name)
        if e and e.get('probe_seconds') and e.get('probe_kernel_seconds') is not None:
            notes.append(f'{name}: {e.get("launches_per_pass", "?")} kernel launches per pass of '
                         f'{e.get("spp_per_pass", "?")} spp; one pass took {1e3 * e["probe_seconds"]:.1f} ms, '
                         f'of which kernels {1e3 * e["probe_kernel_seconds"]:.1f} ms (the rest is host '
                         'overhead: tracing, launches).')
    md += [''] + ['- ' + n for n in notes]
    if lg and 'line' in lg:
        md += ['', f'lightgraph: `{lg["line"]}`']
    text = '\n'.join(md) + '\n'
    print(text, flush=True)
    if a.out:
        with open(a.out, 'w') as f:
            f.write(text)
    if a.json_out:
        with open(a.json_out, 'w') as f:
            json.dump(result, f, indent=1)


# ----------------------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest='cmd', required=True)

    r = sub.add_parser('render', help='time Mitsuba on mi.cornell_box() and write the average image')
    r.add_argument('--variant', default='cuda_ad_rgb', help='mitsuba variant (default cuda_ad_rgb; '
                   'scalar_rgb or llvm_ad_rgb for a smoke test elsewhere)')
    r.add_argument('--mode', choices=('megakernel', 'wavefront'), default='megakernel',
                   help='megakernel (Dr.Jit symbolic loops, the default) or wavefront (evaluated loops)')
    r.add_argument('--res', type=parse_res, default=(1280, 720), help='WxH (default 1280x720)')
    r.add_argument('--spp-per-pass', type=int, default=16, help='samples per pixel of each pass (default 16)')
    r.add_argument('--seconds', type=float, default=10.0,
                   help='render passes until this much timed rendering has accumulated (default 10)')
    r.add_argument('--passes', type=int, default=None, help='render exactly this many passes instead')
    r.add_argument('--seed', type=int, default=1000, help='seed of the first timed pass (then +1 per pass)')
    r.add_argument('--out', default=None, help='write the average as a float32 RGB EXR here')
    r.add_argument('--scene-xml', default=None,
                   help='render this exported scene (lightgraph export --format mitsuba --res WxH) '
                        'instead of mi.cornell_box(); its integrator and film come from the file')
    r.set_defaults(func=cmd_render)

    m = sub.add_parser('rmse', help='RMSE / relMSE of EXRs against a reference EXR')
    m.add_argument('--reference', required=True, help='reference EXR')
    m.add_argument('--image', action='append', required=True, metavar='NAME=PATH.exr',
                   help='image to compare (repeatable)')
    m.add_argument('--emitter-threshold', type=float, default=EMITTER_THRESHOLD,
                   help='reference radiance (max channel) from which a pixel counts as the light\'s and '
                        f'is left out of "RMSE without light pixels" (default {EMITTER_THRESHOLD}; inf: none)')
    m.add_argument('--variant', default=None,
                   help='mitsuba variant used only to read EXRs (default: scalar_rgb if the build has '
                        'it, else cuda_ad_rgb or llvm_ad_rgb)')
    m.set_defaults(func=cmd_rmse)

    s = sub.add_parser('summary', help='Markdown summary of a run_gpu.sh run (needs no mitsuba)')
    s.add_argument('--res', type=parse_res, default=(1280, 720))
    s.add_argument('--seconds', type=float, required=True, help='the equal-time budget')
    s.add_argument('--layout', default='NaivePTsk')
    s.add_argument('--lightgraph-log', help="lightgraph render's stderr (equal-time run)")
    s.add_argument('--reference-log', help="lightgraph render's stderr (reference run)")
    s.add_argument('--mitsuba-json', action='append', default=[], help='JSON lines of render (repeatable)')
    s.add_argument('--rmse-json', help='JSON lines of rmse')
    s.add_argument('--device', default=None)
    s.add_argument('--title', default=None)
    s.add_argument('--max-depth', type=int, default=MAX_DEPTH, help='for the header line')
    s.add_argument('--rr-depth', type=int, default=RR_DEPTH, help='for the header line')
    s.add_argument('--out', help='write the Markdown here')
    s.add_argument('--json-out', help='write all numbers as JSON here')
    s.set_defaults(func=cmd_summary)

    a = ap.parse_args()
    if a.cmd == 'rmse':
        a.variant = pick_reader_variant(a.variant)
    a.func(a)


def pick_reader_variant(wanted):
    """Reading EXRs works with any variant. The slim wheel has no scalar_rgb, and a variant may be
    installed but unusable on a machine (cuda_* without a GPU, llvm_* without libLLVM), so by
    default take the first one that can be set. An explicit --variant is taken as it is
    (import_mitsuba checks it)."""
    if wanted is not None:
        return wanted
    try:
        import mitsuba as mi
    except ImportError:
        return 'scalar_rgb'  # import_mitsuba() then says how to install it
    available = installed_variants(mi)
    ordered = [v for v in ('scalar_rgb', 'cuda_ad_rgb', 'llvm_ad_rgb') if v in available]
    ordered += [v for v in available if v not in ordered]
    for v in ordered:
        try:
            mi.set_variant(v)
            return v
        except Exception:
            continue
    return ordered[0] if ordered else 'scalar_rgb'  # import_mitsuba() then says why it fails


if __name__ == '__main__':
    main()
