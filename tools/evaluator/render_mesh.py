#!/usr/bin/python3
"""Render an error-coloured PLY mesh (vertex x y z [nx ny nz] red green blue, triangle faces)
to a PNG with a small software rasteriser (numpy + cv2.fillConvexPoly in painter's order).

The camera is derived only from the ground-truth mesh (so every mesh rendered against the
same --gt gets the SAME camera): look-at from an oblique view above the room, the ceiling
removed (triangles whose centroid is above --cut-z, default GT top - 0.3 m), and back faces
culled (so the near wall, seen from outside, does not hide the room: "dollhouse" view).

usage: render_mesh.py mesh_error.ply out.png --gt gt_mesh.ply [--json eval.json] [--name NAME]
"""
import argparse, json, math, os, sys, time
import numpy as np
import cv2

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plyio import read_ply


def load(path):
    m = read_ply(path)
    v = m['vertex']
    P = np.stack([v['x'], v['y'], v['z']], 1).astype(np.float64)
    C = (np.stack([v['red'], v['green'], v['blue']], 1).astype(np.float64)
         if 'red' in v else np.full((len(P), 3), 200.0))
    N = np.stack([v['nx'], v['ny'], v['nz']], 1).astype(np.float64) if 'nx' in v else None
    return P, C, N, m['face']


def look_at(eye, target, up):
    f = target - eye; f /= np.linalg.norm(f)
    r = np.cross(f, up); r /= np.linalg.norm(r)
    d = np.cross(f, r)              # image "down" (camera y down, z forward)
    return np.stack([r, d, f])      # rows: camera axes in world


def make_camera(gt_path, args):
    P, _, _, F = load(gt_path)
    up = np.zeros(3); up[args.up_axis] = args.up_sign
    h = P @ up
    cut = args.cut_z if args.cut_z is not None else h.max() - 0.3
    keep = (P[F].mean(1) @ up) <= cut
    Pk = P[np.unique(F[keep])]
    lo, hi = Pk.min(0), Pk.max(0)
    target = 0.5 * (lo + hi)
    target = target - up * (target @ up) + up * (h.min() + args.target_h)
    # horizontal basis perpendicular to up
    a = np.eye(3)[(args.up_axis + 1) % 3]; b = np.cross(up, a)
    az, el = math.radians(args.azimuth), math.radians(args.elevation)
    back = math.cos(el) * (math.cos(az) * a + math.sin(az) * b) + math.sin(el) * up
    eye = target + args.distance * back
    R = look_at(eye, target, up)
    Xc = (Pk - eye) @ R.T
    u, v = Xc[:, 0] / Xc[:, 2], Xc[:, 1] / Xc[:, 2]
    W, H = args.width, args.height
    top = args.top_margin          # room for the title
    f = min((W * 0.94) / (u.max() - u.min()), ((H - top) * 0.92) / (v.max() - v.min()))
    cx = W / 2 - f * 0.5 * (u.max() + u.min())
    cy = top + (H - top) / 2 - f * 0.5 * (v.max() + v.min())
    return dict(eye=eye, target=target, R=R, f=f, cx=cx, cy=cy, cut=cut, up=up,
                azimuth_deg=args.azimuth, elevation_deg=args.elevation, distance_m=args.distance)


def render(P, C, N, F, cam, W, H, ss, cull=True):
    up = cam['up']
    cen = P[F].mean(1)
    keep = (cen @ up) <= cam['cut']
    F = F[keep]; cen = cen[keep]
    p0, p1, p2 = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
    fn = np.cross(p1 - p0, p2 - p0)
    ln = np.linalg.norm(fn, axis=1); ok = ln > 0
    fn[ok] /= ln[ok, None]
    if N is not None:                       # orient by the stored vertex normals
        s = np.sign((fn * N[F].mean(1)).sum(1)); s[s == 0] = 1; fn *= s[:, None]
    view = cam['eye'] - cen
    facing = (fn * view).sum(1) > 0
    if cull:
        ok &= facing
    F, cen, fn = F[ok], cen[ok], fn[ok]
    # flat colour = mean vertex colour, Lambert from face normal (two-sided), light from camera side + up
    light = (cam['eye'] - cam['target']); light /= np.linalg.norm(light)
    light = light + 0.6 * up; light /= np.linalg.norm(light)
    lam = np.abs(fn @ light)
    shade = 0.35 + 0.65 * lam
    col = C[F].mean(1) * shade[:, None]     # RGB
    # project
    R = cam['R']
    Xc = (P - cam['eye']) @ R.T
    z = Xc[:, 2].clip(1e-6)
    uv = np.stack([cam['f'] * Xc[:, 0] / z + cam['cx'], cam['f'] * Xc[:, 1] / z + cam['cy']], 1) * ss
    depth = (cen - cam['eye']) @ R[2]
    order = np.argsort(-depth)               # far first (painter's)
    SHIFT = 4
    tri = np.round(uv[F[order]] * (1 << SHIFT)).astype(np.int32)   # (n,3,2)
    bgr = np.round(col[order][:, ::-1]).clip(0, 255).astype(np.int32)
    img = np.full((H * ss, W * ss, 3), 255, np.uint8)
    fill = cv2.fillConvexPoly
    for t, c in zip(tri, bgr.tolist()):
        fill(img, t, c, cv2.LINE_8, SHIFT)
    return cv2.resize(img, (W, H), interpolation=cv2.INTER_AREA), len(F)


def err_colour(mm, tol=40.0):
    # evaluator's ramp: blue 0, green tol/2, yellow tol, red 2 tol (RGB)
    xs = [0, tol / 2, tol, 2 * tol]
    cs = np.array([[0, 0, 255], [0, 255, 0], [255, 255, 0], [255, 0, 0]], float)
    return np.stack([np.interp(mm, xs, cs[:, k]) for k in range(3)], -1)


def legend(img, tol=40.0):
    H, W = img.shape[:2]
    bw, bh = 320, 16
    x0, y0 = W - bw - 40, H - 60
    mm = np.linspace(0, 2 * tol, bw)
    bar = err_colour(mm, tol)[:, ::-1].astype(np.uint8)
    img[y0:y0 + bh, x0:x0 + bw] = bar[None]
    cv2.rectangle(img, (x0 - 1, y0 - 1), (x0 + bw, y0 + bh), (0, 0, 0), 1)
    font = cv2.FONT_HERSHEY_SIMPLEX
    for val, txt in [(0, '0'), (tol / 2, '%g' % (tol / 2)), (tol, '%g' % tol), (2 * tol, '>=%g mm' % (2 * tol))]:
        x = x0 + int(round(val / (2 * tol) * (bw - 1)))
        cv2.line(img, (x, y0 + bh), (x, y0 + bh + 5), (0, 0, 0), 1)
        (tw, _), _ = cv2.getTextSize(txt, font, 0.45, 1)
        tx = min(max(x - tw // 2, 0), W - tw - 4)
        cv2.putText(img, txt, (tx, y0 + bh + 20), font, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(img, 'distance to ground truth', (x0, y0 - 8), font, 0.5, (0, 0, 0), 1, cv2.LINE_AA)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('mesh'); ap.add_argument('out')
    ap.add_argument('--gt', required=True, help='ground-truth mesh (defines camera and ceiling cut)')
    ap.add_argument('--json', help="evaluator's --json output, for the title numbers")
    ap.add_argument('--name', help='title name (default: mesh file name)')
    ap.add_argument('--width', type=int, default=1200); ap.add_argument('--height', type=int, default=900)
    ap.add_argument('--supersample', type=int, default=2)
    ap.add_argument('--up-axis', type=int, default=2, help='0/1/2 = x/y/z (hall: z up)')
    ap.add_argument('--up-sign', type=float, default=1.0)
    ap.add_argument('--cut-z', type=float, help='drop triangles with centroid above this height (default GT top - 0.3)')
    ap.add_argument('--azimuth', type=float, default=-115.0, help='deg, direction of the eye from the target, around up')
    ap.add_argument('--elevation', type=float, default=60.0, help='deg above horizontal of the view ray (looking down)')
    ap.add_argument('--distance', type=float, default=12.0, help='m, eye to target')
    ap.add_argument('--target-h', type=float, default=0.5, help='m above the GT floor the camera looks at')
    ap.add_argument('--top-margin', type=int, default=70)
    ap.add_argument('--no-cull', action='store_true')
    ap.add_argument('--tolerance-mm', type=float, default=40.0)
    a = ap.parse_args()
    t0 = time.time()
    cam = make_camera(a.gt, a)
    P, C, N, F = load(a.mesh)
    img, ndraw = render(P, C, N, F, cam, a.width, a.height, a.supersample, cull=not a.no_cull)
    legend(img, a.tolerance_mm)
    font = cv2.FONT_HERSHEY_SIMPLEX
    name = a.name or os.path.basename(a.mesh)
    cv2.putText(img, name, (15, 28), font, 0.75, (0, 0, 0), 2, cv2.LINE_AA)
    if a.json:
        j = json.load(open(a.json))
        acc = j['accuracy_m']
        line = ('accuracy median %.1f mm  p90 %.1f mm  p99 %.1f mm  >10cm %.2f %%   completeness %.2f %%   F %.2f %%'
                % (acc['median'] * 1e3, acc['p90'] * 1e3, acc['p99'] * 1e3, acc['share_over_10cm'] * 100,
                   j['completeness'] * 100, j['f_score'] * 100))
        cv2.putText(img, line, (15, 56), font, 0.55, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(img, 'ceiling cut above %.2f m, back faces culled' % cam['cut'], (15, a.height - 15), font, 0.45,
                (90, 90, 90), 1, cv2.LINE_AA)
    cv2.imwrite(a.out, img)
    print('wrote %s  (%d triangles drawn of %d, %.1f s)' % (a.out, ndraw, len(F), time.time() - t0))
    print('camera: eye %s target %s azimuth %.0f deg elevation %.0f deg f %.1f px cut %.2f m'
          % (np.round(cam['eye'], 3).tolist(), np.round(cam['target'], 3).tolist(), cam['azimuth_deg'],
             cam['elevation_deg'], cam['f'], cam['cut']))


if __name__ == '__main__':
    main()
