#!/usr/bin/env python3
"""gen_tess_scene.py TRIANGLES OUTDIR: the cornell box with its tall box replaced by a bumpy
ball of about TRIANGLES triangles (binary PLY, smooth normals), for the scaling benchmark.
The box's other meshes are copied from the shipped scene (scene paths must be relative)."""
import math
import os
import shutil
import struct
import sys
from array import array

TOP = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def ball(path, tris, center=(0.35, 0.45, -0.3), radius=0.42):
    # a UV sphere: rings x segments quads, two triangles each (the pole rows degenerate)
    n = max(4, int(math.sqrt(tris / 2)))
    rings, segs = n, n
    p, nrm = array('f'), array('f')
    for i in range(rings + 1):
        th = math.pi * i / rings
        st, ct = math.sin(th), math.cos(th)
        for j in range(segs):
            ph = 2 * math.pi * j / segs
            # a gentle bump so the surface is not a sphere the BVH could exploit
            r = radius * (1 + 0.04 * math.sin(7 * th) * math.cos(5 * ph))
            x, y, z = st * math.cos(ph), ct, st * math.sin(ph)
            p.extend((center[0] + r * x, center[1] + r * y, center[2] + r * z))
            nrm.extend((x, y, z))
    faces = bytearray()
    pack = struct.Struct('<Biii').pack
    for i in range(rings):
        a0, b0 = i * segs, (i + 1) * segs
        for j in range(segs):
            j1 = (j + 1) % segs
            faces += pack(3, a0 + j, b0 + j, b0 + j1)
            faces += pack(3, a0 + j, b0 + j1, a0 + j1)
    nv, nf = (rings + 1) * segs, 2 * rings * segs
    vert = array('f')
    for k in range(nv):
        vert.extend(p[3 * k:3 * k + 3])
        vert.extend(nrm[3 * k:3 * k + 3])
    if sys.byteorder != 'little':
        vert.byteswap()
    with open(path, 'wb') as f:
        f.write(('ply\nformat binary_little_endian 1.0\nelement vertex %d\n'
                 'property float x\nproperty float y\nproperty float z\n'
                 'property float nx\nproperty float ny\nproperty float nz\n'
                 'element face %d\nproperty list uchar int vertex_indices\nend_header\n' % (nv, nf)).encode())
        f.write(vert.tobytes())
        f.write(faces)
    return nf


def main():
    if len(sys.argv) != 3:
        sys.exit('usage: gen_tess_scene.py TRIANGLES OUTDIR')
    tris, out = int(sys.argv[1]), sys.argv[2]
    os.makedirs(out, exist_ok=True)
    nf = ball(os.path.join(out, 'ball.ply'), tris)
    src = open(os.path.join(TOP, 'scenes', 'cornell-box', 'scene.xml')).read()
    shutil.copytree(os.path.join(TOP, 'scenes', 'cornell-box', 'meshes'), os.path.join(out, 'meshes'), dirs_exist_ok=True)
    tall = src.index('<shape type="obj"><string name="filename" value="meshes/06_TallBox.obj"/>')
    end = src.index('</shape>', tall) + len('</shape>')
    src = (src[:tall] + '<shape type="ply"><string name="filename" value="ball.ply"/>\n'
           '    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.725, 0.71, 0.68"/></bsdf></bsdf>\n'
           '  </shape>' + src[end:])
    open(os.path.join(out, 'scene.xml'), 'w').write(src)
    print('%s: %d triangles in the ball' % (os.path.join(out, 'scene.xml'), nf))


if __name__ == '__main__':
    main()
