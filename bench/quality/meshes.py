"""Mesh geometry for the quality suite, written with numpy and scipy only so that
no score comes from the code under test: OBJ reading, signed distance to a body,
plane slices and boundary loops carried by their edge parameters, similarity
alignment, flipped faces and mirror partners."""
import numpy as np
from scipy.spatial import cKDTree


def read_obj(path):
    """Positions (every `v` line, in order) and polygon faces (0-based index lists)."""
    verts, faces = [], []
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            if line.startswith("v "):
                verts.append(line.split()[1:4])
            elif line.startswith("f "):
                idx = []
                for tok in line.split()[1:]:
                    i = int(tok.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(verts) + i)
                faces.append(idx)
    return np.asarray(verts, dtype=float), faces


def read_positions(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        return np.asarray([l.split()[1:4] for l in f if l.startswith("v ")], dtype=float)


def fan_triangles(faces, with_owner=False):
    """The faces' fan triangles (f0, fk, fk+1); with_owner: and each one's face."""
    tris = [(f[0], f[k], f[k + 1]) for f in faces for k in range(1, len(f) - 1)]
    tris = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
    if not with_owner:
        return tris
    return tris, np.repeat(np.arange(len(faces)), [max(len(f) - 2, 0) for f in faces])


def _closest_on_triangles(p, a, b, c):
    """Closest points on triangles (a, b, c) to points p, all (n, 3) (Ericson's method, vectorised)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    denom = va + vb + vc
    denom = np.where(np.abs(denom) < 1e-30, 1e-30, denom)
    v, w = vb / denom, vc / denom
    out = a + ab * v[:, None] + ac * w[:, None]  # interior
    # Edge and vertex regions, later assignments winning in Ericson's order reversed.
    with np.errstate(divide="ignore", invalid="ignore"):
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        m = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
        out[m] = (b + (c - b) * t_bc[:, None])[m]
        t_ac = d2 / (d2 - d6)
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        out[m] = (a + ac * t_ac[:, None])[m]
        t_ab = d1 / (d1 - d3)
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        out[m] = (a + ab * t_ab[:, None])[m]
    m = (d6 >= 0) & (d5 <= d6)
    out[m] = c[m]
    m = (d3 >= 0) & (d4 <= d3)
    out[m] = b[m]
    m = (d1 <= 0) & (d2 <= 0)
    out[m] = a[m]
    return out


class Body:
    """A closed triangle mesh: signed distance (negative inside) of query points."""

    def __init__(self, path):
        self.vertices, faces = read_obj(path)
        self.tris = fan_triangles(faces)
        t = self.vertices[self.tris]
        self.normals = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        self.normals /= np.maximum(np.linalg.norm(self.normals, axis=1), 1e-30)[:, None]
        self.centres = t.mean(axis=1)
        self.radius = np.linalg.norm(t - self.centres[:, None, :], axis=2).max()
        self.tree = cKDTree(self.centres)

    def closest_candidates(self, p, k=24):
        """For points p (n, 3): the k triangles with the nearest centres (n, k), the
        points repeated k times, each triangle's closest point and its distance (n, k)."""
        _, cand = self.tree.query(p, k=k)
        n, kk = cand.shape
        pp = np.repeat(p, kk, axis=0)
        tri = self.tris[cand.ravel()]
        q = _closest_on_triangles(pp, self.vertices[tri[:, 0]], self.vertices[tri[:, 1]], self.vertices[tri[:, 2]])
        return cand, pp, q, np.linalg.norm(pp - q, axis=1).reshape(n, kk)

    def signed_distance(self, points, k=24):
        points = np.asarray(points, dtype=float)
        out = np.empty(len(points))
        for s in range(0, len(points), 20000):
            p = points[s:s + 20000]
            cand, pp, q, d = self.closest_candidates(p, k)
            n, kk = cand.shape
            best = d.min(axis=1)
            # Sign: among the candidates as close as the closest, the one whose normal
            # is most aligned with p - q (a closest point on an edge or a vertex).
            diff = (pp - q).reshape(n, kk, 3)
            nrm = self.normals[cand.ravel()].reshape(n, kk, 3)
            cosang = np.einsum("ijk,ijk->ij", diff, nrm) / np.maximum(d, 1e-30)
            tie = d <= best[:, None] + 1e-9
            score = np.where(tie, np.abs(cosang), -1.0)
            pick = score.argmax(axis=1)
            sign = np.sign(cosang[np.arange(n), pick])
            sign[sign == 0] = 1.0
            out[s:s + 20000] = sign * best
        return out


def weld_ids(positions, tol=1e-4):
    """Coincident vertices (a soup, split seams) share one id."""
    keys = np.round(positions / tol).astype(np.int64)
    _, ids = np.unique(keys, axis=0, return_inverse=True)
    return ids.ravel()


def _chain(segments):
    """Segments as pairs of hashable point keys -> list of polylines (lists of keys), longest first."""
    adj = {}
    for a, b in segments:
        if a == b:
            continue
        adj.setdefault(a, []).append(b)
        adj.setdefault(b, []).append(a)
    seen_edge = set()
    chains = []
    starts = [k for k, v in adj.items() if len(v) == 1] + list(adj.keys())
    for s in starts:
        for nxt in adj[s]:
            if (s, nxt) in seen_edge:
                continue
            chain = [s]
            cur, prev = s, None
            step = nxt
            while True:
                seen_edge.add((cur, step))
                seen_edge.add((step, cur))
                chain.append(step)
                prev, cur = cur, step
                options = [x for x in adj[cur] if (cur, x) not in seen_edge]
                if not options:
                    break
                step = options[0]
            chains.append(chain)
    chains.sort(key=len, reverse=True)
    return chains


class Carried:
    """Points on a garment as (i, j, t): (1 - t) x_i + t x_j, carried to any state."""

    def __init__(self, i, j, t):
        self.i, self.j, self.t = np.asarray(i), np.asarray(j), np.asarray(t, dtype=float)

    def on(self, positions):
        return (1 - self.t)[:, None] * positions[self.i] + self.t[:, None] * positions[self.j]

    def __len__(self):
        return len(self.t)


def slice_curve(positions, faces, ids, point, normal, near, start=None, end=None):
    """The garment cut by a plane: the piece nearest `near`, clipped between the points
    nearest `start` and `end`, as a Carried polyline (None if the plane misses)."""
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    s = (positions - np.asarray(point, float)) @ normal
    keyinfo = {}
    segments = []
    for f in faces:
        hits = []
        for k in range(len(f)):
            a, b = f[k], f[(k + 1) % len(f)]
            sa, sb = s[a], s[b]
            if (sa < 0) != (sb < 0):
                t = sa / (sa - sb)
                ka, kb = ids[a], ids[b]
                key = (ka, kb) if ka < kb else (kb, ka)
                if key not in keyinfo:
                    keyinfo[key] = (a, b, t)
                hits.append(key)
        for h in range(0, len(hits) - 1, 2):
            segments.append((hits[h], hits[h + 1]))
    if not segments:
        return None
    chains = _chain(segments)
    pts = lambda chain: np.array([(1 - keyinfo[k][2]) * positions[keyinfo[k][0]] + keyinfo[k][2] * positions[keyinfo[k][1]] for k in chain])
    near = np.asarray(near, float)
    best = min(chains, key=lambda c: np.linalg.norm(pts(c) - near, axis=1).min())
    p = pts(best)
    if start is not None and end is not None:
        a = int(np.linalg.norm(p - np.asarray(start, float), axis=1).argmin())
        b = int(np.linalg.norm(p - np.asarray(end, float), axis=1).argmin())
        lo, hi = min(a, b), max(a, b)
        best = best[lo:hi + 1]
    info = [keyinfo[k] for k in best]
    return Carried([x[0] for x in info], [x[1] for x in info], [x[2] for x in info])


def boundary_loops(positions, faces, ids):
    """Boundary loops of the faces (edges used once after welding), as vertex index lists."""
    count = {}
    rep = {}
    for f in faces:
        for k in range(len(f)):
            a, b = f[k], f[(k + 1) % len(f)]
            key = (ids[a], ids[b]) if ids[a] < ids[b] else (ids[b], ids[a])
            count[key] = count.get(key, 0) + 1
            rep.setdefault(ids[a], a)
            rep.setdefault(ids[b], b)
    segs = [k for k, c in count.items() if c == 1]
    chains = _chain(segs)
    return [[rep[k] for k in c] for c in chains]


def boundary_curve(positions, faces, ids, near):
    loops = boundary_loops(positions, faces, ids)
    near = np.asarray(near, float)
    best = min(loops, key=lambda l: np.linalg.norm(positions[l] - near, axis=1).min())
    return Carried(best, best, np.zeros(len(best)))


def umeyama(x, y):
    """The similarity taking x onto y (n, 3) in the least squares sense (Umeyama): rotation r,
    scale s and the centroids mx, my (x maps to s (x - mx) r^T + my)."""
    mx, my = x.mean(0), y.mean(0)
    xc, yc = x - mx, y - my
    cov = yc.T @ xc / len(x)
    u, sv, vt = np.linalg.svd(cov)
    d = np.ones(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        d[-1] = -1
    r = u @ np.diag(d) @ vt
    var = (xc ** 2).sum() / len(x)
    return r, (sv * d).sum() / max(var, 1e-30), mx, my


def similarity_rms(x, y):
    """RMS distance between x and y (n, 3) after the best similarity alignment of x onto y (Umeyama)."""
    r, scale, mx, my = umeyama(x, y)
    aligned = scale * (x - mx) @ r.T + my
    return float(np.sqrt(((aligned - y) ** 2).sum(1).mean()))


def shape_error(curve, original):
    """The project's shape error, recomputed: RMS after similarity / the original's length."""
    length = np.linalg.norm(np.diff(original, axis=0), axis=1).sum()
    return similarity_rms(curve, original) / max(length, 1e-30)


def face_normals(positions, faces):
    """Newell normals (not normalised) of polygon faces."""
    out = np.zeros((len(faces), 3))
    for k in range(max(len(f) for f in faces)):
        idx = [(f[k % len(f)], f[(k + 1) % len(f)]) if k < len(f) else (f[0], f[0]) for f in faces]
        a = positions[[i for i, _ in idx]]
        b = positions[[j for _, j in idx]]
        out[:, 0] += (a[:, 1] - b[:, 1]) * (a[:, 2] + b[:, 2])
        out[:, 1] += (a[:, 2] - b[:, 2]) * (a[:, 0] + b[:, 0])
        out[:, 2] += (a[:, 0] - b[:, 0]) * (a[:, 1] + b[:, 1])
    return out


def flipped_faces(original, result, faces):
    """Faces whose normal in `result` points against the original normal turned by the
    best rotation of the face's neighbourhood (its vertices and those of the faces
    sharing a vertex with it): folds, not the garment's own bending."""
    import scipy.sparse as sp
    nv = len(original)
    rows = np.repeat(np.arange(len(faces)), [len(f) for f in faces])
    cols = np.concatenate([np.asarray(f) for f in faces])
    inc = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(faces), nv))
    hood = ((inc @ inc.T) @ inc)
    hood.data[:] = 1.0
    count = np.asarray(hood.sum(axis=1)).ravel()
    mx = (hood @ original) / count[:, None]
    my = (hood @ result) / count[:, None]
    h = np.zeros((len(faces), 3, 3))
    for a in range(3):
        for b in range(3):
            h[:, a, b] = hood @ (original[:, a] * result[:, b]) - count * mx[:, a] * my[:, b]
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(u @ vt))
    u[:, :, 2] *= d[:, None]
    rot = np.transpose(u @ vt, (0, 2, 1))  # maps original -> result directions
    n0 = face_normals(original, faces)
    n1 = face_normals(result, faces)
    ok = (np.linalg.norm(n0, axis=1) > 1e-12) & (np.linalg.norm(n1, axis=1) > 1e-12)
    turned = np.einsum("fij,fj->fi", rot, n0)
    return int(((np.einsum("fi,fi->f", turned, n1) < 0) & ok).sum())


def face_samples(positions, faces, m=5):
    """Points inside every face and the face each belongs to: per fan triangle the
    centroids of its subdivision into (m + 1)^2 small triangles pointing the same way
    (21 points for m = 5). Four points per triangle (the centroid and three near the
    corners' middles) missed the body poking through coarse faces between them by up
    to 0.07 cm on the shared garments."""
    tris, owner = fan_triangles(faces, with_owner=True)
    n = m + 1
    bary = np.array([(1.0 - (i + 1 / 3) / n - (j + 1 / 3) / n, (i + 1 / 3) / n, (j + 1 / 3) / n)
                     for i in range(n) for j in range(n - i)])
    pts = np.einsum("sk,tkd->tsd", bary, positions[tris]).reshape(-1, 3)
    return pts, np.repeat(owner, len(bary))


def face_probes(positions, faces, body_vertices):
    """The points of every face right over the body's vertices near it: per fan
    triangle, each body vertex within its reach whose projection onto the
    triangle's plane falls inside the triangle, and that projection. Where a
    body vertex rises through a coarse face between its sample points (the top
    of a bump: a face is highest over the body there), the projection lies
    inside the body. Returns (points, owner face)."""
    tris, owner = fan_triangles(faces, with_owner=True)
    if not len(tris):
        return np.zeros((0, 3)), np.zeros(0, dtype=np.int64)
    t = positions[tris]
    centre = t.mean(axis=1)
    reach = np.linalg.norm(t - centre[:, None, :], axis=2).max(axis=1) + 1.0
    tree = cKDTree(body_vertices)
    dot = lambda x, y: np.einsum("ij,ij->i", x, y)
    pts, own = [], []
    for s in range(0, len(t), 50000):  # bounded memory on dense garments
        near = tree.query_ball_point(centre[s:s + 50000], reach[s:s + 50000])
        count = np.fromiter((len(n) for n in near), dtype=np.int64, count=len(near))
        tri = s + np.repeat(np.arange(len(near)), count)
        vert = np.fromiter((i for n in near for i in n), dtype=np.int64, count=int(count.sum()))
        a, ab, ac = t[tri, 0], t[tri, 1] - t[tri, 0], t[tri, 2] - t[tri, 0]
        av = body_vertices[vert] - a
        d00, d01, d11 = dot(ab, ab), dot(ab, ac), dot(ac, ac)
        det = d00 * d11 - d01 * d01
        ok = det > 1e-12 * d00 * d11
        det = np.where(ok, det, 1.0)
        u = (d11 * dot(av, ab) - d01 * dot(av, ac)) / det
        v = (d00 * dot(av, ac) - d01 * dot(av, ab)) / det
        keep = ok & (u >= 0) & (v >= 0) & (u + v <= 1)
        pts.append(a[keep] + u[keep, None] * ab[keep] + v[keep, None] * ac[keep])
        own.append(owner[tri[keep]])
    return np.concatenate(pts), np.concatenate(own)


def mirror_partners(positions, centre_x=0.0, tol=0.3):
    """For each vertex, the vertex at its mirror image about x = centre_x (or -1)."""
    tree = cKDTree(positions)
    mirrored = positions.copy()
    mirrored[:, 0] = 2 * centre_x - mirrored[:, 0]
    d, j = tree.query(mirrored)
    j[d > tol] = -1
    return j


def face_pairs(faces):
    """The two faces of every edge that exactly two faces share (vertex indices), (m, 2)."""
    edges = {}
    for fi, f in enumerate(faces):
        for k in range(len(f)):
            a, b = f[k], f[(k + 1) % len(f)]
            if a != b:
                edges.setdefault((min(a, b), max(a, b)), []).append(fi)
    return np.asarray([v for v in edges.values() if len(v) == 2], dtype=np.int64).reshape(-1, 2)


def welded_face_pairs(positions, faces):
    """Coincident vertices welded (weld_ids: a soup's faces meet along their edges),
    the faces on the welded vertices and their face_pairs: the edges creases are
    counted on. Returns (ids, welded faces, pairs)."""
    ids = weld_ids(positions)
    rep = np.empty(ids.max() + 1, dtype=np.int64)
    rep[ids] = np.arange(len(ids))
    welded = [[int(rep[ids[v]]) for v in f] for f in faces]
    return ids, welded, np.asarray(face_pairs(welded))


def dihedral_change(original, result, faces, pairs=None):
    """Per edge of face_pairs(faces) (or the `pairs` given, made by it once for
    several results), the change of the angle between its two faces' normals from
    `original` to `result`, in degrees: a fold line or a groove the result adds (a
    pinch) shows as a large change along a few edges, while a smooth bend of a fine
    mesh spreads small ones."""
    if pairs is None:
        pairs = face_pairs(faces)
    if len(pairs) == 0:
        return np.zeros(0)

    def angles(x):
        n = face_normals(x, faces)
        n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
        cos = np.clip(np.einsum("ij,ij->i", n[pairs[:, 0]], n[pairs[:, 1]]), -1.0, 1.0)
        return np.degrees(np.arccos(cos))

    return np.abs(angles(result) - angles(original))


def components(positions, faces, ids):
    """Per vertex: its piece (faces connected through welded vertices `ids`)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components
    rows = [ids[f[k]] for f in faces for k in range(len(f))]
    cols = [ids[f[(k + 1) % len(f)]] for f in faces for k in range(len(f))]
    n = ids.max() + 1
    _, label = connected_components(sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n)), directed=False)
    return label[ids]


def _outward(body, p):
    """Unit directions away from `body` at points p: from the closest body point
    (inside: towards it), or the closest triangle's normal on the surface."""
    cand, _, q, d = body.closest_candidates(p)
    n, kk = cand.shape
    pick = d.argmin(axis=1)
    q = q.reshape(n, kk, 3)[np.arange(n), pick]
    away = p - q
    length = np.linalg.norm(away, axis=1)
    sign = np.sign(body.signed_distance(p))
    sign[sign == 0] = 1.0
    out = away * (sign / np.maximum(length, 1e-30))[:, None]
    flat = length < 0.05
    out[flat] = body.normals[cand[np.arange(n), pick]][flat]
    return out


def _line_hits(o, d, a, b, c):
    """Where lines o + t d (n, 3) cross triangles (a, b, c) (n, k, 3): t, nan where not."""
    e1, e2 = b - a, c - a
    h = np.cross(d[:, None, :], e2)
    det = np.einsum("nkj,nkj->nk", e1, h)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = o[:, None, :] - a
    u = np.einsum("nkj,nkj->nk", s, h) * inv
    q = np.cross(s, e1)
    v = np.einsum("nkj,nj->nk", q, d) * inv
    t = np.einsum("nkj,nkj->nk", q, e2) * inv
    return np.where(ok & (u >= 0) & (v >= 0) & (u + v <= 1), t, np.nan)


def layer_covers(positions, faces, piece, body, reach=3.0, k=48):
    """Vertices with another piece's surface over them: the line from the body out
    through the vertex crosses a triangle of another piece within `reach` beyond
    it (and none of that piece behind it nearer). Returns (vertex, piece) pairs."""
    tris = fan_triangles(faces)
    tri_piece = piece[tris[:, 0]]
    tree = cKDTree(positions[tris].mean(axis=1))
    d = _outward(body, positions)
    _, cand = tree.query(positions, k=min(k, len(tris)))
    t = _line_hits(positions, d, positions[tris[cand, 0]], positions[tris[cand, 1]], positions[tris[cand, 2]])
    other = tri_piece[cand] != piece[:, None]
    t = np.where(other & (np.abs(t) < reach), t, np.nan)
    pairs = []
    for v in np.nonzero(np.isfinite(t).any(axis=1))[0]:
        for p in np.unique(tri_piece[cand[v]][np.isfinite(t[v])]):
            tv = t[v][np.isfinite(t[v]) & (tri_piece[cand[v]] == p)]
            if tv[np.argmin(np.abs(tv))] > 0.02:
                pairs.append((int(v), int(p)))
    return pairs


def layers_crossed(positions, faces, piece, body, pairs, k=48):
    """Of the (vertex, piece) pairs of layer_covers on the input, those whose
    vertex lies beyond that piece here (the nearest crossing of the line behind
    it): an inner layer through an outer one. Returns (count, deepest cm)."""
    if not pairs:
        return 0, 0.0
    tris = fan_triangles(faces)
    tri_piece = piece[tris[:, 0]]
    v = np.array([p[0] for p in pairs])
    want = np.array([p[1] for p in pairs])
    tree = cKDTree(positions[tris].mean(axis=1))
    d = _outward(body, positions[v])
    _, cand = tree.query(positions[v], k=min(k, len(tris)))
    t = _line_hits(positions[v], d, positions[tris[cand, 0]], positions[tris[cand, 1]], positions[tris[cand, 2]])
    t = np.where((tri_piece[cand] == want[:, None]) & (np.abs(t) < 3.0), t, np.nan)
    has = np.isfinite(t).any(axis=1)
    nearest = np.full(len(v), np.nan)
    nearest[has] = t[has][np.arange(has.sum()), np.nanargmin(np.abs(t[has]), axis=1)]
    behind = has & (nearest < 0)
    return int(behind.sum()), float(-nearest[behind].min()) if behind.any() else 0.0
