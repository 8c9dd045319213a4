#!/usr/bin/env python3
"""Vertex-clustering decimation of a Wavefront OBJ (positions and triangles only).

    python3 tools/decimate_obj.py IN.obj OUT.obj CELL

Every vertex moves to the mean of the vertices in its cube of side CELL; triangles that
collapse or repeat are dropped. Used to make scenes/meshes/bunny_lowpoly.obj from the Stanford
bunny so that the raster PRT baker's per-vertex renders stay affordable on a CPU Vulkan device.
"""
import sys


def main():
    src, dst, cell = sys.argv[1], sys.argv[2], float(sys.argv[3])
    verts, faces, header = [], [], []
    for line in open(src):
        if line.startswith("v "):
            verts.append(tuple(map(float, line.split()[1:4])))
        elif line.startswith("f "):
            idx = [int(p.split("/")[0]) for p in line.split()[1:]]
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
            for k in range(1, len(idx) - 1):
                faces.append((idx[0], idx[k], idx[k + 1]))
    cluster, sums = {}, []
    remap = []
    for v in verts:
        key = tuple(int(c // cell) for c in v)
        if key not in cluster:
            cluster[key] = len(sums)
            sums.append([0.0, 0.0, 0.0, 0])
        c = cluster[key]
        s = sums[c]
        s[0] += v[0]
        s[1] += v[1]
        s[2] += v[2]
        s[3] += 1
        remap.append(c)
    seen, out_faces = set(), []
    for f in faces:
        a, b, c = (remap[i] for i in f)
        if a == b or b == c or c == a:
            continue
        key = tuple(sorted((a, b, c)))
        if key in seen:
            continue
        seen.add(key)
        out_faces.append((a, b, c))
    used = sorted({i for f in out_faces for i in f})
    index = {old: new for new, old in enumerate(used)}
    with open(dst, "w") as out:
        out.write(f"# {src.split('/')[-1]} decimated by tools/decimate_obj.py, cell {cell}\n")
        out.write(f"# {len(used)} vertices, {len(out_faces)} triangles\n")
        for i in used:
            s = sums[i]
            out.write("v %.6f %.6f %.6f\n" % (s[0] / s[3], s[1] / s[3], s[2] / s[3]))
        for a, b, c in out_faces:
            out.write(f"f {index[a] + 1} {index[b] + 1} {index[c] + 1}\n")
    print(f"{dst}: {len(used)} vertices, {len(out_faces)} triangles")


if __name__ == "__main__":
    main()
