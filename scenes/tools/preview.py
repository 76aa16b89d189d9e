#!/usr/bin/env python3
"""Independent sanity checker for the shipped scenes (standard library only, slow, tiny images).

    python3 scenes/tools/preview.py [--ambient] scenes/ajar-door/scene.xml [out.png] [size]

Parses the scene XML itself (Mitsuba 0.6 conventions: transform composition order, lookat,
rectangle/cube/sphere/obj, flipNormals, one-sided area emitters, twosided) and renders a
direct-lighting-only image (next-event estimation, all surfaces treated as opaque and matte)
to a PNG, so framing, light orientation and light leaks can be checked without the renderer.
Reports: triangle count; each area light's world normal; primary rays that hit the back of a
one-sided (non-twosided, non-dielectric) surface (shown magenta, should be 0); primary rays that
see an emitter's front; pixels that escape the scene (shown blue)."""
import math
import os
import random
import struct
import sys
import xml.etree.ElementTree as ET
import zlib


# ---- small linear algebra ----------------------------------------------------------------
def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def add(a, b): return (a[0] + b[0], a[1] + b[1], a[2] + b[2])
def mul(a, s): return (a[0] * s, a[1] * s, a[2] * s)
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def cross(a, b): return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
def norm(a):
    l = math.sqrt(dot(a, a))
    return (a[0] / l, a[1] / l, a[2] / l)


def mat_mul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def ident():
    return [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]


def xf_point(M, p):
    return tuple(M[i][0] * p[0] + M[i][1] * p[1] + M[i][2] * p[2] + M[i][3] for i in range(3))


def xf_vec(M, v):
    return tuple(M[i][0] * v[0] + M[i][1] * v[1] + M[i][2] * v[2] for i in range(3))


def nums(s):
    return [float(x) for x in s.replace(",", " ").split()]


def parse_transform(el):
    M = ident()
    for c in el:
        g = lambda k, d=0.0: float(c.get(k, d))
        if c.tag == "translate":
            T = ident()
            if c.get("value"):
                T[0][3], T[1][3], T[2][3] = nums(c.get("value"))
            else:
                T[0][3], T[1][3], T[2][3] = g("x"), g("y"), g("z")
        elif c.tag == "scale":
            T = ident()
            if c.get("value"):
                v = nums(c.get("value"))
                v = v * 3 if len(v) == 1 else v
            else:
                v = (g("x", 1), g("y", 1), g("z", 1))
            T[0][0], T[1][1], T[2][2] = v
        elif c.tag == "rotate":
            a = norm((g("x"), g("y"), g("z")))
            th = math.radians(g("angle"))
            cs, sn = math.cos(th), math.sin(th)
            x, y, z = a
            R = [[cs + x * x * (1 - cs), x * y * (1 - cs) - z * sn, x * z * (1 - cs) + y * sn],
                 [y * x * (1 - cs) + z * sn, cs + y * y * (1 - cs), y * z * (1 - cs) - x * sn],
                 [z * x * (1 - cs) - y * sn, z * y * (1 - cs) + x * sn, cs + z * z * (1 - cs)]]
            T = ident()
            for i in range(3):
                for j in range(3):
                    T[i][j] = R[i][j]
        elif c.tag == "matrix":
            v = nums(c.get("value"))
            T = [v[0:4], v[4:8], v[8:12], v[12:16]]
        elif c.tag == "lookat":
            o, t, u = nums(c.get("origin")), nums(c.get("target")), nums(c.get("up"))
            d = norm(sub(t, o))
            left = norm(cross(u, d))
            nu = cross(d, left)
            T = [[left[0], nu[0], d[0], o[0]], [left[1], nu[1], d[1], o[1]],
                 [left[2], nu[2], d[2], o[2]], [0, 0, 0, 1]]
        else:
            raise ValueError("unsupported transform element " + c.tag)
        M = mat_mul(T, M)
    return M


# ---- scene -------------------------------------------------------------------------------
class Mat:
    def __init__(self, kind, color, twosided):
        self.kind, self.color, self.twosided = kind, color, twosided


def parse_bsdf(el, ids):
    if el.tag == "ref":
        return ids[el.get("id")]
    kind = el.get("type")
    if kind == "twosided":
        inner = parse_bsdf([c for c in el if c.tag in ("bsdf", "ref")][0], ids)
        return Mat(inner.kind, inner.color, True)
    color = (0.5, 0.5, 0.5)
    for c in el:
        if c.get("name") in ("reflectance", "diffuseReflectance"):
            if c.tag == "rgb":
                color = tuple(nums(c.get("value")))
            elif c.tag == "texture":
                color = (0.5, 0.5, 0.5)
    if kind in ("conductor", "roughconductor"):
        color = (0.8, 0.7, 0.4)
        if kind == "roughconductor":
            dist = [c.get("value") for c in el if c.get("name") == "distribution"]
            assert dist == ["ggx"], "roughconductor without distribution ggx"
    if kind == "roughplastic":
        dist = [c.get("value") for c in el if c.get("name") == "distribution"]
        assert dist == ["ggx"], "roughplastic without distribution ggx"
    if kind == "dielectric":
        color = (0.9, 0.9, 1.0)
    return Mat(kind, color, False)


CUBE_FACES = [  # outward normal, CCW seen from outside
    ((1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1)),
    ((-1, -1, 1), (-1, 1, 1), (-1, 1, -1), (-1, -1, -1)),
    ((-1, 1, -1), (-1, 1, 1), (1, 1, 1), (1, 1, -1)),
    ((-1, -1, 1), (-1, -1, -1), (1, -1, -1), (1, -1, 1)),
    ((-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)),
    ((1, -1, -1), (-1, -1, -1), (-1, 1, -1), (1, 1, -1)),
]


class Shape:
    def __init__(self):
        self.tris = []   # (p0, e1, e2, n_unit, area)
        self.sphere = None
        self.flip = False
        self.mat = None
        self.Le = None
        self.lo = self.hi = None

    def add_tri(self, a, b, c):
        e1, e2 = sub(b, a), sub(c, a)
        n = cross(e1, e2)
        l = math.sqrt(dot(n, n))
        if l == 0:
            return
        self.tris.append((a, e1, e2, mul(n, 1 / l), l / 2))

    def finish(self):
        if self.sphere:
            c, r = self.sphere
            self.lo, self.hi = sub(c, (r, r, r)), add(c, (r, r, r))
        else:
            pts = [t[0] for t in self.tris] + [add(t[0], t[1]) for t in self.tris] + [add(t[0], t[2]) for t in self.tris]
            self.lo = tuple(min(p[i] for p in pts) - 1e-4 for i in range(3))
            self.hi = tuple(max(p[i] for p in pts) + 1e-4 for i in range(3))
        self.area = (4 * math.pi * self.sphere[1] ** 2) if self.sphere else sum(t[4] for t in self.tris)


def load_obj(path, M, shape, flip):
    vs = []
    for line in open(path):
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            vs.append(xf_point(M, tuple(float(x) for x in w[1:4])))
        elif w[0] == "f":
            idx = [int(x.split("/")[0]) for x in w[1:]]
            idx = [i - 1 if i > 0 else len(vs) + i for i in idx]
            for k in range(1, len(idx) - 1):
                a, b, c = vs[idx[0]], vs[idx[k]], vs[idx[k + 1]]
                if flip:
                    shape.add_tri(a, c, b)
                else:
                    shape.add_tri(a, b, c)


def load(path):
    root = ET.parse(path).getroot()
    base = os.path.dirname(path)
    ids, shapes, cam = {}, [], None
    info = {"maxDepth": None, "integrator": None}
    for el in root:
        if el.tag == "integrator":
            info["integrator"] = el.get("type")
            for c in el:
                if c.get("name") == "maxDepth":
                    info["maxDepth"] = int(c.get("value"))
        elif el.tag == "bsdf":
            ids[el.get("id")] = parse_bsdf(el, ids)
        elif el.tag == "sensor":
            fov, M, W, H = None, None, 256, 256
            for c in el:
                if c.get("name") == "fov":
                    fov = float(c.get("value"))
                elif c.tag == "transform":
                    M = parse_transform(c)
                elif c.tag == "string" and c.get("name") == "fovAxis":
                    assert c.get("value") == "x"
                elif c.tag == "film":
                    for f in c:
                        if f.get("name") == "width":
                            W = int(f.get("value"))
                        if f.get("name") == "height":
                            H = int(f.get("value"))
            cam = (fov, M, W, H)
        elif el.tag == "shape":
            s = Shape()
            M = ident()
            kind = el.get("type")
            flip = False
            center, radius, fname = (0, 0, 0), 1.0, None
            for c in el:
                n = c.get("name")
                if c.tag == "transform":
                    M = parse_transform(c)
                elif n == "flipNormals":
                    flip = c.get("value") == "true"
                elif c.tag in ("bsdf", "ref"):
                    s.mat = parse_bsdf(c, ids)
                elif c.tag == "emitter":
                    assert c.get("type") == "area"
                    s.Le = tuple(nums([x for x in c if x.get("name") == "radiance"][0].get("value")))
                elif n == "center":
                    center = (float(c.get("x")), float(c.get("y")), float(c.get("z")))
                elif n == "radius":
                    radius = float(c.get("value"))
                elif n == "filename":
                    fname = c.get("value")
            s.flip = flip
            if kind == "sphere":
                s.sphere = (center, radius)
            elif kind == "rectangle":
                q = [xf_point(M, p) for p in ((-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0))]
                if flip:
                    q = q[::-1]
                s.add_tri(q[0], q[1], q[2]); s.add_tri(q[0], q[2], q[3])
            elif kind == "cube":
                for f in CUBE_FACES:
                    q = [xf_point(M, p) for p in f]
                    if flip:
                        q = q[::-1]
                    s.add_tri(q[0], q[1], q[2]); s.add_tri(q[0], q[2], q[3])
            elif kind == "obj":
                load_obj(os.path.join(base, fname), M, s, flip)
            else:
                raise ValueError("unsupported shape " + kind)
            s.finish()
            shapes.append(s)
    return cam, shapes, info


# ---- ray tracing -------------------------------------------------------------------------
def hit_box(o, inv, lo, hi, tmax):
    t0, t1 = 1e-6, tmax
    for i in range(3):
        a = (lo[i] - o[i]) * inv[i]
        b = (hi[i] - o[i]) * inv[i]
        if a > b:
            a, b = b, a
        if a > t0:
            t0 = a
        if b < t1:
            t1 = b
        if t0 > t1:
            return False
    return True


def intersect(shapes, o, d, tmax=1e30, eps=1e-5):
    inv = tuple(1.0 / x if x != 0 else 1e30 for x in d)
    best = None
    for si, s in enumerate(shapes):
        if not hit_box(o, inv, s.lo, s.hi, tmax):
            continue
        if s.sphere:
            c, r = s.sphere
            oc = sub(o, c)
            b = dot(oc, d)
            cc = dot(oc, oc) - r * r
            disc = b * b - cc
            if disc < 0:
                continue
            sq = math.sqrt(disc)
            for t in (-b - sq, -b + sq):
                if eps < t < tmax:
                    p = add(o, mul(d, t))
                    n = norm(sub(p, c))
                    if s.flip:
                        n = mul(n, -1)
                    tmax, best = t, (t, si, n)
                    break
            continue
        for (p0, e1, e2, n, _) in s.tris:
            pv = cross(d, e2)
            det = dot(e1, pv)
            if abs(det) < 1e-12:
                continue
            idet = 1.0 / det
            tv = sub(o, p0)
            u = dot(tv, pv) * idet
            if u < 0 or u > 1:
                continue
            qv = cross(tv, e1)
            v = dot(d, qv) * idet
            if v < 0 or u + v > 1:
                continue
            t = dot(e2, qv) * idet
            if eps < t < tmax:
                tmax, best = t, (t, si, n)
    return best


def sample_light(s, rng):
    if s.sphere:
        c, r = s.sphere
        z = 1 - 2 * rng.random()
        ph = 2 * math.pi * rng.random()
        rr = math.sqrt(max(0, 1 - z * z))
        n = (rr * math.cos(ph), rr * math.sin(ph), z)
        p = add(c, mul(n, r))
        return p, (mul(n, -1) if s.flip else n)
    x = rng.random() * s.area
    for (p0, e1, e2, n, a) in s.tris:
        if x <= a:
            break
        x -= a
    u, v = rng.random(), rng.random()
    if u + v > 1:
        u, v = 1 - u, 1 - v
    return add(p0, add(mul(e1, u), mul(e2, v))), n


AMBIENT = 0.0


def render(path, out_png=None, size=64, nl=4, seed=1):
    cam, shapes, info = load(path)
    rng = random.Random(seed)
    fov, M, W, H = cam
    W, H = size, size * cam[3] // cam[2]
    o = xf_point(M, (0, 0, 0))
    tx = math.tan(math.radians(fov) / 2)
    ty = tx * H / W
    lights = [s for s in shapes if s.Le]
    img = []
    stats = {"backface": 0, "emitter": 0, "escape": 0, "lit": 0}
    for j in range(H):
        for i in range(W):
            # +x camera axis is image-left in Mitsuba
            sx = -(2 * (i + 0.5) / W - 1) * tx
            sy = (1 - 2 * (j + 0.5) / H) * ty
            d = norm(xf_vec(M, (sx, sy, 1)))
            h = intersect(shapes, o, d)
            if not h:
                img.append((0, 0, 1)); stats["escape"] += 1
                continue
            t, si, n = h
            s = shapes[si]
            p = add(o, mul(d, t))
            front = dot(n, d) < 0
            if s.Le and front:
                img.append(s.Le); stats["emitter"] += 1
                continue
            if not front:
                if s.mat.twosided or s.mat.kind == "dielectric":
                    n = mul(n, -1)
                else:
                    img.append((1, 0, 1)); stats["backface"] += 1
                    continue
            L = [0.0, 0.0, 0.0]
            if AMBIENT:  # geometry view: a little light from the eye, to check framing
                for k in range(3):
                    L[k] += AMBIENT * s.mat.color[k] * -dot(n, d)
            for ls in lights:
                for _ in range(nl):
                    q, nq = sample_light(ls, rng)
                    w = sub(q, p)
                    r2 = dot(w, w)
                    w = mul(w, 1 / math.sqrt(r2))
                    c1, c2 = dot(n, w), -dot(nq, w)
                    if c1 <= 0 or c2 <= 0:
                        continue
                    po = add(p, mul(n, 1e-4))
                    hh = intersect(shapes, po, w, math.sqrt(r2) * (1 - 1e-4))
                    if hh:
                        continue
                    g = c1 * c2 / r2 * ls.area / nl
                    for k in range(3):
                        L[k] += ls.Le[k] * s.mat.color[k] / math.pi * g
            if max(L) > 0:
                stats["lit"] += 1
            img.append(tuple(L))
    if out_png:
        write_png(out_png, W, H, img)
    return shapes, info, stats, (W, H)


def write_png(path, W, H, img):
    def tm(x):
        x = max(0.0, min(1.0, x))
        return int(255 * (x ** (1 / 2.2)) + 0.5)
    raw = b"".join(b"\0" + bytes(tm(c) for px in img[j * W:(j + 1) * W] for c in px) for j in range(H))
    def chunk(t, data):
        return struct.pack(">I", len(data)) + t + data + struct.pack(">I", zlib.crc32(t + data) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def check(path, out_png=None, size=48):
    shapes, info, stats, (W, H) = render(path, out_png, size)
    ntri = sum(len(s.tris) for s in shapes)
    print("%s: integrator %s maxDepth %s, %d shapes, %d triangles, %d exact spheres"
          % (path, info["integrator"], info["maxDepth"], len(shapes), ntri, sum(1 for s in shapes if s.sphere)))
    for s in shapes:
        if s.Le:
            if s.sphere:
                print("  area light: sphere, normals %s" % ("inward" if s.flip else "outward"))
            else:
                ns = set(tuple(round(x, 3) for x in t[3]) for t in s.tris)
                c = mul(add(s.lo, s.hi), 0.5)
                print("  area light: centre %s, area %.3f, normal(s) %s" % (tuple(round(x, 3) for x in c), s.area, sorted(ns)))
    print("  %dx%d primary rays: back faces of one-sided surfaces %d, emitter %d, escaped %d, directly lit %d"
          % (W, H, stats["backface"], stats["emitter"], stats["escape"], stats["lit"]))
    bad = stats["backface"]  # escapes are legitimate in open scenes (cornell-box front, the slit)
    if ntri > 20000:
        print("  TOO MANY TRIANGLES"); bad += 1
    return bad


if __name__ == "__main__":
    if "--ambient" in sys.argv:  # add eye light so unlit geometry shows
        sys.argv.remove("--ambient")
        AMBIENT = 0.3
    p = sys.argv[1]
    out = sys.argv[2] if len(sys.argv) > 2 else None
    size = int(sys.argv[3]) if len(sys.argv) > 3 else 48
    sys.exit(1 if check(p, out, size) else 0)
