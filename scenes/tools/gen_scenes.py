#!/usr/bin/env python3
"""Generates the shipped scenes' XML files (scenes/<name>/scene.xml) from the descriptions
below, in the Mitsuba 0.6 subset pcbpt reads (DESIGN.md section 5). Standard library only.

    python3 scenes/tools/gen_scenes.py          # rewrite every scene.xml
    python3 scenes/tools/gen_scenes.py --check  # also verify them with preview.py's model

Geometry uses only the built-in shapes: rooms are built from solid, slightly overlapping wall
slabs (`cube`, outward normals, so every wall seen from inside a room is a front face and no
crack can leak light); lights are `rectangle`s whose (one-sided) normal is checked below.
The Cornell box is the exception: it is Benedikt Bitterli's CC0 geometry (OBJ files copied
verbatim into scenes/cornell-box/meshes/), identical to ../shared/scenes/cornell-box-bitterli.
"""
import math
import os
import struct
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)  # scenes/


def fmt(v):
    if isinstance(v, (tuple, list)):
        return ", ".join(fmt(x) for x in v)
    r = round(float(v), 6)
    if r == 0:
        r = 0.0
    s = ("%.6f" % r).rstrip("0").rstrip(".")
    return s if s not in ("", "-0") else "0"


class Scene:
    def __init__(self, name, method, max_depth, comment):
        self.name, self.method, self.max_depth, self.comment = name, method, max_depth, comment
        self.lines = []
        self.tris = 0           # triangle count (sphere shapes are exact, counted 0)
        self.lights = []        # (description, expected normal) for rectangle emitters
        self.preview = True     # preview.py models the scene (it has no environment emitters)

    def camera(self, origin, target, up, fov, fov_axis=None):
        L = self.lines
        L.append('  <sensor type="perspective">')
        L.append('    <float name="fov" value="%s"/>' % fmt(fov))
        if fov_axis:
            L.append('    <string name="fovAxis" value="%s"/>' % fov_axis)
        L.append('    <transform name="toWorld"><lookat origin="%s" target="%s" up="%s"/></transform>'
                 % (fmt(origin), fmt(target), fmt(up)))
        L.append('    <film type="hdrfilm"><integer name="width" value="256"/>'
                 '<integer name="height" value="256"/></film>')
        L.append('  </sensor>')

    def bsdf(self, ident, body):
        """Declares a top-level BSDF referenced later with ref id=..."""
        self.lines.append('  <bsdf type="%s" id="%s">%s</bsdf>' % (body[0], ident, body[1]))

    def _shape(self, kind, params, xform, mat, emit=None, flip=False):
        L = self.lines
        L.append('  <shape type="%s">' % kind)
        for p in params:
            L.append('    ' + p)
        if xform:
            L.append('    <transform name="toWorld">%s</transform>' % "".join(xform))
        if flip:
            L.append('    <boolean name="flipNormals" value="true"/>')
        L.append('    ' + mat)
        if emit is not None:
            L.append('    <emitter type="area"><rgb name="radiance" value="%s"/></emitter>' % fmt(emit))
        L.append('  </shape>')

    def box(self, lo, hi, mat, rot_y=None, pivot=None):
        """Solid box [lo, hi] (world, axis aligned), optionally rotated by rot_y degrees about
        the vertical axis through `pivot` (default: its centre)."""
        c = [(a + b) / 2 for a, b in zip(lo, hi)]
        h = [(b - a) / 2 for a, b in zip(lo, hi)]
        x = ['<scale x="%s" y="%s" z="%s"/>' % (fmt(h[0]), fmt(h[1]), fmt(h[2]))]
        if rot_y:
            p = pivot or c
            x.append('<translate x="%s" y="%s" z="%s"/>' % (fmt(c[0] - p[0]), fmt(c[1] - p[1]), fmt(c[2] - p[2])))
            x.append('<rotate x="0" y="1" z="0" angle="%s"/>' % fmt(rot_y))
            x.append('<translate x="%s" y="%s" z="%s"/>' % (fmt(p[0]), fmt(p[1]), fmt(p[2])))
        else:
            x.append('<translate x="%s" y="%s" z="%s"/>' % (fmt(c[0]), fmt(c[1]), fmt(c[2])))
        self._shape("cube", [], x, mat)
        self.tris += 12

    # rotation taking the rectangle's +z normal to each axis direction (Mitsuba rotate is
    # right-handed about the axis; checked numerically in check_rect_normals)
    RECT_ROT = {"+z": None, "-z": ("y", 180), "+y": ("x", -90), "-y": ("x", 90),
                "+x": ("y", 90), "-x": ("y", -90)}

    def rect(self, center, half_u, half_v, normal, mat, emit=None):
        """Rectangle of half sizes (half_u, half_v) along its local x and y, facing `normal`
        (one of +x -x +y -y +z -z), centred at `center`."""
        x = ['<scale x="%s" y="%s" z="1"/>' % (fmt(half_u), fmt(half_v))]
        r = self.RECT_ROT[normal]
        if r:
            ax = {"x": 'x="1" y="0" z="0"', "y": 'x="0" y="1" z="0"'}[r[0]]
            x.append('<rotate %s angle="%s"/>' % (ax, fmt(r[1])))
        x.append('<translate x="%s" y="%s" z="%s"/>' % (fmt(center[0]), fmt(center[1]), fmt(center[2])))
        self._shape("rectangle", [], x, mat, emit)
        self.tris += 2
        if emit is not None:
            self.lights.append((center, normal))

    def sphere(self, center, radius, mat, emit=None, flip=False):
        self._shape("sphere", ['<point name="center" x="%s" y="%s" z="%s"/>' % tuple(fmt(c) for c in center),
                               '<float name="radius" value="%s"/>' % fmt(radius)], None, mat, emit, flip)

    def raw(self, text):
        self.lines.append(text)

    def write(self):
        d = os.path.join(ROOT, self.name)
        os.makedirs(d, exist_ok=True)
        out = ['<?xml version="1.0"?>',
               '<!-- %s -->' % self.comment,
               '<!-- Generated by scenes/tools/gen_scenes.py: edit that, not this file. -->',
               '<scene version="0.6.0">',
               '  <integrator type="%s"><integer name="maxDepth" value="%d"/></integrator>'
               % (self.method, self.max_depth)]
        out += self.lines
        out.append('</scene>')
        with open(os.path.join(d, "scene.xml"), "w") as f:
            f.write("\n".join(out) + "\n")
        return os.path.join(d, "scene.xml")


def diffuse(rgb):
    return '<bsdf type="diffuse"><rgb name="reflectance" value="%s"/></bsdf>' % fmt(rgb)


def ref(ident):
    return '<ref id="%s"/>' % ident


BLACK = diffuse((0, 0, 0))
WALL = (0.7, 0.7, 0.7)


def shell(s, lo, hi, mat, t=0.1, skip=()):
    """Closed room [lo, hi] from six solid slabs of thickness t outside it; the slabs overlap
    at the edges (each spans the full outer extent along the directions it does not face)."""
    olo = [a - t for a in lo]
    ohi = [b + t for b in hi]
    for axis in range(3):
        for side in (0, 1):
            tag = "xyz"[axis] + ("-" if side == 0 else "+")
            if tag in skip:
                continue
            a, b = list(olo), list(ohi)
            if side == 0:
                b[axis] = lo[axis]
            else:
                a[axis] = hi[axis]
            s.box(a, b, mat)


# ------------------------------------------------------------------------------------------
def cornell_box():
    """Bitterli's Cornell box (same geometry, materials, light and camera as
    ../shared/scenes/cornell-box-bitterli); only the default integrator is pcbpt."""
    s = Scene("cornell-box", "pcbpt", 11,
              "Cornell box: Bitterli's CC0 geometry (same as ../shared/scenes/cornell-box-bitterli), "
              "light radiance (17,12,4) facing down; maxDepth 11 = pbrt maxdepth 10")
    s.camera((0, 1, 6.8), (0, 1, 0), (0, 1, 0), 19.5)
    white, red, green = (0.725, 0.71, 0.68), (0.63, 0.065, 0.05), (0.14, 0.45, 0.091)
    for fn, c in (("00_Floor", white), ("01_Ceiling", white), ("02_BackWall", white),
                  ("03_RightWall", green), ("04_LeftWall", red), ("05_ShortBox", white),
                  ("06_TallBox", white)):
        s.raw('  <shape type="obj"><string name="filename" value="meshes/%s.obj"/>\n'
              '    <bsdf type="twosided">%s</bsdf>\n  </shape>' % (fn, diffuse(c)))
    s.raw('  <shape type="obj"><string name="filename" value="meshes/07_Light.obj"/>\n'
          '    %s\n    <emitter type="area"><rgb name="radiance" value="17, 12, 4"/></emitter>\n'
          '  </shape>' % BLACK)
    s.tris = 5 * 2 + 2 * 12 + 2
    return s


def furnace():
    s = Scene("furnace", "path", -1,
              "White furnace: closed inward-facing emitting sphere, Le=1, diffuse albedo a=0.5; "
              "exact radiance everywhere = Le*sum_{k<d} a^k for maxDepth d (2 for d=-1)")
    s.camera((0.05, 0.02, 0.1), (0.05, 0.02, -1), (0, 1, 0), 60)
    s.sphere((0, 0, 0), 1.0, diffuse((0.5, 0.5, 0.5)), emit=(1, 1, 1), flip=True)
    return s


def ajar_door():
    """Room A (camera, x<0) and room B (light, x>0) share a wall x in [-0.05, 0.05] with a door
    opening z in [-0.5, 0.5], y in [0, 2]. The door (1.1 wide so that, closed, it would overlap
    the frame by 5 cm each side; 2.1 high) hangs on room A's side, hinged at z=-0.55, and is
    opened 6 degrees into room A (rotation -6 about +y): light from B reaches A only through the narrow wedge between
    door and wall (open at the door's free edge and above the door)."""
    s = Scene("ajar-door", "pcbpt", -1,
              "Door ajar (Veach): two rooms joined by a door opened a crack; the only light is on "
              "the ceiling of the hidden room, so the camera's room is lit through the gap")
    s.camera((-3.8, 1.5, 1.7), (0, 0.9, -0.2), (0, 1, 0), 65)
    s.bsdf("wall", ("diffuse", '<rgb name="reflectance" value="0.7, 0.7, 0.7"/>'))
    s.bsdf("floor", ("diffuse", '<rgb name="reflectance" value="0.55, 0.45, 0.35"/>'))
    s.bsdf("door", ("diffuse", '<rgb name="reflectance" value="0.6, 0.4, 0.25"/>'))
    lo, hi = (-4.0, 0.0, -2.0), (3.0, 2.5, 2.0)
    shell(s, lo, hi, ref("wall"), skip=("y-",))
    s.box((-4.1, -0.1, -2.1), (3.1, 0.0, 2.1), ref("floor"))
    # dividing wall with the door opening (pieces overlap the shell by 1 cm)
    s.box((-0.05, -0.01, -2.01), (0.05, 2.51, -0.5), ref("wall"))
    s.box((-0.05, -0.01, 0.5), (0.05, 2.51, 2.01), ref("wall"))
    s.box((-0.05, 2.0, -0.51), (0.05, 2.51, 0.51), ref("wall"))
    # the door: closed it would be [-0.09,-0.05] x [0,2.1] x [-0.55,0.55]. Rotating by theta
    # about +y maps (x, z) to (x cos + z sin, -x sin + z cos), so theta = -6 deg at the hinge
    # (-0.05, *, -0.55) swings the free edge to x = -0.05 - 1.1 sin 6 = -0.165, into room A
    # (checked in check_door below; +6 would push it through the opening and seal it)
    s.box((-0.09, 0.0, -0.55), (-0.05, 2.1, 0.55), ref("door"), rot_y=-6.0, pivot=(-0.05, 0.0, -0.55))
    # light: ceiling panel of room B, facing down
    s.rect((1.6, 2.49, 0.0), 0.5, 0.5, "-y", BLACK, emit=(1500, 1500, 1500))
    # furniture in room A
    s.box((-2.4, 0.0, -1.7), (-1.6, 0.8, -0.9), ref("wall"), rot_y=20)
    s.box((-1.2, 0.0, 1.1), (-0.6, 1.2, 1.7), '<bsdf type="plastic"><rgb name="diffuseReflectance" '
          'value="0.2, 0.3, 0.6"/><float name="intIOR" value="1.5"/></bsdf>', rot_y=-15)
    s.sphere((-1.0, 0.35, -1.2), 0.35, diffuse((0.6, 0.6, 0.2)))
    return s


def slit_room():
    """Room [-2,2] x [0,2.5] x [-2,2]; the back wall (z=-2) is a 2 cm thick blind with a 5 cm
    high horizontal slit at y in [1.60, 1.65], x in [-1.5, 1.5]. Outside, 3 m behind it and above
    the slit, a big emitter faces the wall (+z): its light enters only through the slit and
    draws a bright strip on the floor; the camera cannot see the emitter through the slit."""
    s = Scene("slit-room", "pcbpt", -1,
              "Slit room: interior lit only through a narrow horizontal slit in a blind by a big "
              "emitter outside")
    s.camera((0.6, 1.1, 1.8), (-0.2, 0.8, -2.0), (0, 1, 0), 75)
    s.bsdf("wall", ("diffuse", '<rgb name="reflectance" value="0.75, 0.75, 0.72"/>'))
    lo, hi = (-2.0, 0.0, -2.0), (2.0, 2.5, 2.0)
    shell(s, lo, hi, ref("wall"), skip=("z-",))
    # blind: thin wall z in [-2.02, -2], overlapping the shell's slabs
    zl, zh = -2.02, -2.0
    s.box((-2.1, -0.1, zl), (2.1, 1.60, zh), ref("wall"))
    s.box((-2.1, 1.65, zl), (2.1, 2.6, zh), ref("wall"))
    s.box((-2.1, 1.59, zl), (-1.5, 1.66, zh), ref("wall"))
    s.box((1.5, 1.59, zl), (2.1, 1.66, zh), ref("wall"))
    # the emitter outside: 6 x 2 m at z=-5, y in [2.5, 4.5], facing +z (toward the blind)
    s.rect((0.0, 3.5, -5.0), 3.0, 1.0, "+z", BLACK, emit=(400, 400, 400))
    # a box and a sphere inside
    s.box((-1.2, 0.0, -0.4), (-0.5, 0.7, 0.3), diffuse((0.65, 0.25, 0.2)), rot_y=30)
    s.sphere((0.9, 0.4, -0.6), 0.4, diffuse((0.25, 0.5, 0.6)))
    return s


def open_room():
    """Big room 10 x 4 x 10 with a 6 x 6 m ceiling panel: nearly every point sees the light."""
    s = Scene("open-room", "pcbpt", -1,
              "Open room: large room with a large, barely occluded ceiling light (direct "
              "connections almost always visible)")
    s.camera((0.0, 2.2, 4.6), (0.0, 0.8, -1.0), (0, 1, 0), 70)
    s.bsdf("wall", ("diffuse", '<rgb name="reflectance" value="0.7, 0.7, 0.7"/>'))
    lo, hi = (-5.0, 0.0, -5.0), (5.0, 4.0, 5.0)
    shell(s, lo, hi, ref("wall"))
    s.rect((0.0, 3.99, 0.0), 3.0, 3.0, "-y", BLACK, emit=(2, 2, 2))
    s.box((-2.5, 0.0, -2.0), (-1.5, 1.0, -1.0), diffuse((0.6, 0.3, 0.2)), rot_y=25)
    s.box((1.0, 0.0, -3.0), (2.0, 2.0, -2.0), diffuse((0.3, 0.5, 0.3)), rot_y=-10)
    s.sphere((0.0, 0.6, -0.5), 0.6, diffuse((0.3, 0.3, 0.6)))
    s.sphere((2.2, 0.4, 0.8), 0.4, '<bsdf type="roughplastic"><string name="distribution" value="ggx"/>'
             '<float name="alpha" value="0.2"/><rgb name="diffuseReflectance" value="0.7, 0.6, 0.2"/></bsdf>')
    return s


def glossy_glass():
    """Closed room 4 x 3 x 4, checkerboard floor, a small bright ceiling light off to the left;
    glass sphere, rough gold sphere, rough plastic cube. The light sits in the back-left corner so
    the glass sphere's caustic (traced: centred about (0.69, 0, -0.42), 0.1 m wide) lands on the floor
    in front-right of the sphere where the camera sees it."""
    s = Scene("glossy-glass", "pcbpt", -1,
              "Glossy and glass: rough gold (GGX 0.15), rough plastic, glass sphere casting a "
              "caustic from a small light, checkerboard floor, closed room")
    s.camera((0.0, 1.6, 1.9), (0.0, 0.5, -0.6), (0, 1, 0), 65)
    s.bsdf("wall", ("diffuse", '<rgb name="reflectance" value="0.7, 0.7, 0.7"/>'))
    lo, hi = (-2.0, 0.0, -2.0), (2.0, 3.0, 2.0)
    s.bsdf("floor", ("diffuse", '<texture type="checkerboard" name="reflectance">'
                     '<rgb name="color0" value="0.8, 0.8, 0.8"/><rgb name="color1" value="0.2, 0.2, 0.2"/>'
                     '<float name="uscale" value="8"/><float name="vscale" value="8"/></texture>'))
    shell(s, lo, hi, ref("wall"))
    # the checkerboard is on a rectangle just above the floor slab so its uv are the plain
    # [0,1]^2 of the rectangle (cube uv are per face and not documented in Mitsuba 0.6)
    s.rect((0.0, 0.0005, 0.0), 2.0, 2.0, "+y", ref("floor"))
    s.rect((-1.6, 2.99, -1.6), 0.2, 0.2, "-y", BLACK, emit=(120, 120, 120))
    s.sphere((0.35, 0.45, -0.6), 0.45, '<bsdf type="dielectric"><float name="intIOR" value="1.5"/>'
             '<float name="extIOR" value="1.0"/></bsdf>')
    s.sphere((-0.75, 0.4, -1.1), 0.4, '<bsdf type="roughconductor"><string name="distribution" value="ggx"/>'
             '<string name="material" value="Au"/><float name="alpha" value="0.15"/></bsdf>')
    s.box((0.9, 0.0, -1.6), (1.5, 0.6, -1.0), '<bsdf type="roughplastic"><string name="distribution" value="ggx"/>'
          '<float name="alpha" value="0.1"/><rgb name="diffuseReflectance" value="0.1, 0.4, 0.15"/></bsdf>', rot_y=30)
    return s


def glossy_floor():
    """Room 8 x 3.5 x 8 whose floor is a near-mirror (rough silver, GGX 0.02) and whose walls are
    glossy (rough plastic, GGX 0.08), under a large 4 x 4 m ceiling panel; two rows of pillars
    and a few blocks stand on the floor. Most of the image is the light and the room seen in the
    floor, so most paths carry glossy vertices, where PCBPT's records (interpolated at diffuse
    vertices) predict the connection PMF badly."""
    s = Scene("glossy-floor", "pcbpt", 8,
              "Glossy-dominated: near-mirror floor, glossy walls, large ceiling light; a hall of pillars")
    s.camera((0.0, 1.7, 3.6), (0.0, 0.9, -2.0), (0, 1, 0), 60)
    s.bsdf("wall", ("roughplastic", '<string name="distribution" value="ggx"/><float name="alpha" value="0.08"/>'
                    '<rgb name="diffuseReflectance" value="0.45, 0.45, 0.5"/>'))
    s.bsdf("mirror", ("roughconductor", '<string name="distribution" value="ggx"/>'
                      '<string name="material" value="Ag"/><float name="alpha" value="0.02"/>'))
    lo, hi = (-4.0, 0.0, -4.0), (4.0, 3.5, 4.0)
    shell(s, lo, hi, ref("wall"), skip=("y-",))
    s.box((-4.1, -0.1, -4.1), (4.1, 0.0, 4.1), ref("mirror"))
    s.rect((0.0, 3.49, -0.5), 2.0, 2.0, "-y", BLACK, emit=(6, 6, 6))
    for i in range(5):  # two rows of pillars, diffuse, 0.3 m square, 3 m high
        z = -3.0 + 1.4 * i
        s.box((-2.3, 0.0, z), (-2.0, 3.0, z + 0.3), diffuse((0.7, 0.68, 0.6)))
        s.box((2.0, 0.0, z), (2.3, 3.0, z + 0.3), diffuse((0.7, 0.68, 0.6)))
    s.box((-0.9, 0.0, -2.2), (-0.1, 0.8, -1.4), diffuse((0.6, 0.25, 0.2)), rot_y=20)
    s.box((0.4, 0.0, -1.2), (1.0, 1.2, -0.6), ref("wall"), rot_y=-25)
    s.sphere((0.9, 0.5, -2.6), 0.5, diffuse((0.2, 0.35, 0.6)))
    return s


def glass_lamp():
    """Room 6 x 3 x 6 lit only by a lamp whose small emitting sphere (r 5 cm) sits inside a
    hollow glass bulb (outer r 0.25, inner r 0.22, IOR 1.5) hanging below the ceiling: every
    light path leaves through two glass interfaces, so next-event estimation never reaches the
    light and eye paths almost never hit it (a tiny emitter behind refraction). A solid glass
    sphere on a table casts a caustic on it; a few boxes and shelves stand around. Only light
    sub-paths (light tracing, and connections from their diffuse vertices) find the light."""
    s = Scene("glass-lamp", "pcbpt", -1,
              "Light only through glass: a small emitter inside a hollow glass bulb lights a room; a "
              "glass ball casts a caustic on a table")
    s.camera((-2.2, 1.6, 2.6), (0.3, 0.8, -0.6), (0, 1, 0), 60)
    s.bsdf("wall", ("diffuse", '<rgb name="reflectance" value="0.7, 0.7, 0.7"/>'))
    s.bsdf("glass", ("dielectric", '<float name="intIOR" value="1.5"/><float name="extIOR" value="1.0"/>'))
    lo, hi = (-3.0, 0.0, -3.0), (3.0, 3.0, 3.0)
    shell(s, lo, hi, ref("wall"))
    lamp = (0.3, 1.9, -0.6)
    s.sphere(lamp, 0.25, ref("glass"))
    s.sphere(lamp, 0.22, ref("glass"), flip=True)   # the bulb's inner surface: glass behind it
    s.sphere(lamp, 0.05, BLACK, emit=(800, 800, 800))
    # table (top and four legs) under the lamp, glass ball on it
    s.box((-0.6, 0.7, -1.4), (1.2, 0.76, 0.2), diffuse((0.65, 0.55, 0.4)))
    for x, z in ((-0.55, -1.35), (1.1, -1.35), (-0.55, 0.1), (1.1, 0.1)):
        s.box((x, 0.0, z), (x + 0.05, 0.7, z + 0.05), diffuse((0.3, 0.2, 0.1)))
    s.sphere((0.5, 0.96, -0.3), 0.2, ref("glass"))
    # shelves on the back wall, a cabinet, a box
    for y in (0.9, 1.5, 2.1):
        s.box((-2.5, y, -3.0), (-0.5, y + 0.04, -2.6), diffuse((0.6, 0.6, 0.55)))
    s.box((1.6, 0.0, -2.9), (2.8, 1.4, -2.3), diffuse((0.3, 0.45, 0.3)))
    s.box((-1.8, 0.0, 0.2), (-1.2, 0.6, 0.8), diffuse((0.6, 0.3, 0.2)), rot_y=30)
    return s


def outdoor():
    """A 200 x 200 m ground with 24 buildings under a 60 x 60 m emitter 80 m up (a cloudy-sky
    stand-in), seen through a narrow (12 degree) camera from 60 m: almost
    every light path lands far outside the view, so light tracing and PCBPT's stored light
    vertices are mostly wasted, while eye paths find the big light easily."""
    s = Scene("outdoor", "pcbpt", -1,
              "Outdoor: a large ground with buildings under a big distant light, seen through a narrow "
              "camera (most light paths land outside the view)")
    s.camera((3.0, 8.0, 60.0), (0.0, 3.0, 0.0), (0, 1, 0), 12)
    s.rect((0.0, 0.0, 0.0), 100.0, 100.0, "+y", diffuse((0.35, 0.33, 0.3)))
    s.rect((0.0, 80.0, 0.0), 30.0, 30.0, "-y", BLACK, emit=(3, 3, 3.3))
    k = 0
    for i in range(-2, 3):
        for j in range(-2, 3):
            if i == 0 and j == 0:
                continue
            h = 4.0 + 3.0 * ((i * 7 + j * 3) % 5)
            x, z = 14.0 * i + 2.0 * j, 14.0 * j - 1.5 * i
            s.box((x - 2.5, 0.0, z - 2.5), (x + 2.5, h, z + 2.5),
                  diffuse((0.5 + 0.05 * (k % 4), 0.45, 0.4 - 0.05 * (k % 3))), rot_y=10.0 * ((k % 5) - 2))
            k += 1
    s.box((-1.5, 0.0, -1.5), (1.5, 6.0, 1.5), diffuse((0.7, 0.7, 0.7)), rot_y=15)
    return s


def write_png(path, w, h, pixel):
    """8-bit RGB PNG (standard library only); pixel(x, y) gives (r, g, b) in 0..255, row 0 at
    the top (Mitsuba reads 8-bit images as sRGB: 255 is exactly 1.0)."""
    raw = b"".join(b"\0" + bytes(c for x in range(w) for c in pixel(x, y)) for y in range(h))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def env_sphere(name, emitter, comment):
    s = Scene(name, "path", -1, comment)
    s.preview = False
    s.camera((0, 0, 4), (0, 0, 0), (0, 1, 0), 40)
    s.sphere((0, 0, 0), 1.0, diffuse((0.5, 0.5, 0.5)))
    s.raw(emitter)
    return s


def env_constant():
    return env_sphere("env-constant", '  <emitter type="constant"><rgb name="radiance" value="2, 2, 2"/></emitter>',
                      "Diffuse sphere (albedo 0.5) under a constant environment L=2: every sphere pixel is "
                      "exactly a*L = 1 (a convex object sees only the environment), the background L = 2")


def env_white_map():
    d = os.path.join(ROOT, "env-white-map")
    os.makedirs(d, exist_ok=True)
    write_png(os.path.join(d, "white.png"), 16, 8, lambda x, y: (255, 255, 255))
    return env_sphere("env-white-map",
                      '  <emitter type="envmap"><string name="filename" value="white.png"/>'
                      '<float name="scale" value="2"/></emitter>',
                      "The env-constant scene lit by an envmap of one colour (white PNG, scale 2): "
                      "must equal the constant emitter, sphere 1 and background 2")


def sky_pixel(x, y, w=64, h=32):
    """A sky: blue above the horizon brightening toward it, a dark ground below, and a small
    sun (4x2 pixels) at 60 degrees azimuth, 30 degrees elevation."""
    theta = (y + 0.5) / h * math.pi
    if abs(x - w // 6) <= 1 and y == h // 3 - 1 or abs(x - w // 6) <= 1 and y == h // 3:
        return (255, 255, 240)
    if theta < math.pi / 2:
        t = theta / (math.pi / 2)
        return (int(70 + 120 * t), int(110 + 100 * t), int(200 + 40 * t))
    return (60, 50, 40)


def env_objects():
    d = os.path.join(ROOT, "env-objects")
    os.makedirs(d, exist_ok=True)
    write_png(os.path.join(d, "sky.png"), 64, 32, sky_pixel)
    s = Scene("env-objects", "pcbpt", -1,
              "Objects on a floor under a sky envmap (rotated 30 degrees about +y) with a small sun: "
              "Beckmann rough conductor, plastic and glass (Mitsuba's default distribution), diffuse; "
              "PT, BDPT and PCBPT must agree")
    s.preview = False
    s.camera((0, 1.4, 3.6), (0, 0.4, 0), (0, 1, 0), 45)
    s.rect((0, 0, 0), 3.0, 3.0, "+y", diffuse((0.6, 0.6, 0.6)))
    s.sphere((-0.8, 0.45, 0), 0.45, '<bsdf type="roughconductor"><string name="material" value="Cu"/>'
             '<float name="alpha" value="0.2"/></bsdf>')
    s.sphere((0.2, 0.35, 0.6), 0.35, diffuse((0.2, 0.5, 0.8)))
    s.box((0.6, 0.0, -0.7), (1.3, 0.7, 0.0), '<bsdf type="roughplastic"><float name="alpha" value="0.3"/>'
          '<rgb name="diffuseReflectance" value="0.7, 0.3, 0.1"/></bsdf>', rot_y=20)
    s.sphere((-0.1, 0.3, -0.9), 0.3, '<bsdf type="roughdielectric"><float name="alpha" value="0.25"/>'
             '<float name="intIOR" value="1.5"/><float name="extIOR" value="1"/></bsdf>')
    s.raw('  <emitter type="envmap"><string name="filename" value="sky.png"/><float name="scale" value="1.5"/>'
          '<transform name="toWorld"><rotate x="0" y="1" z="0" angle="30"/></transform></emitter>')
    return s


def thin_glass():
    """A closed room lit by a ceiling panel; the camera looks through a thin glass pane
    (thindielectric) standing across the room at a rough GGX glass cube, a diffuse sphere and a
    Ward sphere (Mitsuba's default balanced variant) behind them."""
    s = Scene("thin-glass", "pcbpt", -1,
              "Thin glass pane (thindielectric) in front of a rough glass cube (roughdielectric, GGX), "
              "a diffuse sphere and a Ward sphere in a closed room lit by a ceiling panel")
    s.preview = False
    s.camera((0.0, 1.3, 2.6), (0.0, 0.7, -0.5), (0, 1, 0), 60)
    s.bsdf("wall", ("diffuse", '<rgb name="reflectance" value="0.7, 0.7, 0.7"/>'))
    shell(s, (-2.0, 0.0, -2.0), (2.0, 3.0, 3.0), ref("wall"))
    s.rect((0.0, 2.99, 0.0), 0.6, 0.6, "-y", BLACK, emit=(15, 15, 15))
    s.rect((0.0, 0.8, 0.9), 1.2, 0.8, "+z", '<bsdf type="thindielectric"><float name="intIOR" value="1.5"/>'
           '<float name="extIOR" value="1"/></bsdf>')
    s.box((-0.9, 0.0, -0.8), (-0.2, 0.7, -0.1), '<bsdf type="roughdielectric"><string name="distribution" '
          'value="ggx"/><float name="alpha" value="0.15"/><float name="intIOR" value="1.5"/>'
          '<float name="extIOR" value="1"/></bsdf>', rot_y=25)
    s.sphere((0.6, 0.4, -0.6), 0.4, diffuse((0.8, 0.4, 0.2)))
    s.sphere((-0.1, 0.3, -1.5), 0.3, '<bsdf type="ward"><float name="alpha" value="0.2"/>'
             '<rgb name="specularReflectance" value="0.6, 0.45, 0.35"/>'
             '<rgb name="diffuseReflectance" value="0.2, 0.2, 0.3"/></bsdf>')
    return s


def check_door(preview, path):
    """The ajar door must stay on room A's side (x < -0.05) and leave a crack at the frame."""
    _, shapes, _ = preview.load(path)
    door = [s for s in shapes if s.lo[1] > -0.001 and abs(s.hi[1] - 2.1) < 0.01][0]
    pts = [t[0] for t in door.tris] + [preview.add(t[0], t[1]) for t in door.tris]
    xmax = max(p[0] for p in pts)
    # inner face at the frame edge z = 0.5: x of the door's wall-side face there
    th = math.radians(6)
    gap = (0.5 + 0.55) * math.tan(th)
    print("ajar-door: door x max %.4f (must be <= -0.05), crack at the frame edge %.3f m" % (xmax, gap))
    return 0 if xmax <= -0.0499 else 1


SCENES = [cornell_box, furnace, ajar_door, slit_room, open_room, glossy_glass, glossy_floor, glass_lamp, outdoor,
          env_constant, env_white_map, env_objects, thin_glass]


def main():
    paths = []
    for fn in SCENES:
        s = fn()
        p = s.write()
        if s.preview:
            paths.append(p)
        print("%-14s %5d triangles (+ exact spheres)  %s" % (s.name, s.tris, os.path.relpath(p, ROOT)))
    if "--check" in sys.argv:
        sys.path.insert(0, HERE)
        import preview
        bad = 0
        for p in paths:
            bad += preview.check(p)
        bad += check_door(preview, os.path.join(ROOT, "ajar-door", "scene.xml"))
        sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
