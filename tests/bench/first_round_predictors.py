#!/usr/bin/env python3
"""Would a statistic of the mesh predict the samples its default build
needs? For each MESH:M (an OBJ file and the m its default build kept), two
curvature statistics of the surface, and their correlation with m over the
meshes given:

  total |K|    the sum of |angle defect| over the interior vertices;
  disc |K|     the mean, over 1,000 area-uniform points, of |the angle
               defect summed over the vertices within s L1000 of the point|
               (s = 1, 2, 4; L1000 = sqrt(2 A / (sqrt(3) 1000))), the
               curvature a geodesic triangle of the far band can hold.

  /usr/bin/python3 tests/bench/first_round_predictors.py ../shared/meshes/bob_250.obj:1459 ...

Needs numpy (Debian's python3-numpy). Prints one line a mesh, then the
Pearson and Spearman correlations of each statistic with m.
"""

import sys

import numpy as np

SCALES = (1, 2, 4)


def read_obj(path):
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vertices.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(t.split("/")[0]) - 1 for t in line.split()[1:4]])
    return np.array(vertices), np.array(faces)


def angle_defects(v, f):
    """2 pi minus the angle sum at each vertex; 0 on the boundary and at
    unreferenced vertices, where it measures no curvature."""
    p = v[f]
    angles = np.zeros(len(v))
    for k in range(3):
        a = p[:, (k + 1) % 3] - p[:, k]
        b = p[:, (k + 2) % 3] - p[:, k]
        cos = np.einsum("ij,ij->i", a, b) / np.maximum(
            np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300)
        np.add.at(angles, f[:, k], np.arccos(np.clip(cos, -1, 1)))
    defect = 2 * np.pi - angles
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    defect[np.unique(unique[count == 1].ravel())] = 0
    referenced = np.zeros(len(v), bool)
    referenced[f.ravel()] = True
    defect[~referenced] = 0
    return defect


def statistics(path, rng):
    v, f = read_obj(path)
    k = angle_defects(v, f)
    p = v[f]
    face_area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    area = face_area.sum()
    l1000 = np.sqrt(2 * area / (np.sqrt(3) * 1000))
    # Area-uniform points: a face by its area, then a uniform point in it.
    chosen = rng.choice(len(f), 1000, p=face_area / area)
    r = rng.random((1000, 2))
    flip = r.sum(axis=1) > 1
    r[flip] = 1 - r[flip]
    q = p[chosen]
    centres = q[:, 0] + r[:, :1] * (q[:, 1] - q[:, 0]) + r[:, 1:] * (q[:, 2] - q[:, 0])
    disc = []
    for s in SCALES:
        sums = []
        for lo in range(0, len(centres), 100):
            d2 = ((centres[lo:lo + 100, None, :] - v[None, :, :]) ** 2).sum(-1)
            sums.append(np.abs((d2 < (s * l1000) ** 2) @ k))
        disc.append(float(np.concatenate(sums).mean()))
    return float(np.abs(k).sum()), disc


def ranks(x):
    return np.argsort(np.argsort(x))


def main(args):
    if not args:
        print(__doc__)
        return 2
    rng = np.random.default_rng(1)
    names, ms, totals, discs = [], [], [], []
    print("mesh\tm\ttotal |K|\t" + "\t".join(f"disc |K|, {s} L1000" for s in SCALES))
    for arg in args:
        path, m = arg.rsplit(":", 1)
        total, disc = statistics(path, rng)
        names.append(path)
        ms.append(int(m))
        totals.append(total)
        discs.append(disc)
        print(f"{path.rsplit('/', 1)[-1]}\t{m}\t{total:.1f}\t" + "\t".join(f"{d:.3f}" for d in disc))
    ms = np.array(ms)
    columns = [("total |K|", np.array(totals))] + [
        (f"disc |K|, {s} L1000", np.array([d[j] for d in discs])) for j, s in enumerate(SCALES)]
    for label, x in columns:
        pearson = np.corrcoef(ms, x)[0, 1]
        spearman = np.corrcoef(ranks(ms), ranks(x))[0, 1]
        print(f"{label}: Pearson {pearson:.2f}, Spearman {spearman:.2f} with m")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
