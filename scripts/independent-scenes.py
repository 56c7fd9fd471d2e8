#!/usr/bin/env python3
"""Scenes built a different way from `flatland scene`, to try every command on geometry no
default was chosen on (`pip install shapely`; not part of CI).

`flatland scene` draws walls as boxes and rooms on a grid. Here the free space of a building is
one shapely polygon: rooms of irregular sizes, some merged into L-shapes and open plans, door
passages of random widths, furniture (rotated boxes, L-shaped desks), pillars (polygonised
circles, 8-16 sides) and lamps (small emitting squares) cut out of it as holes; a hall is a box
with rotated crates and pillars and two skylights in its ceiling. Every ring is written with the
free space on its left, so every edge is a one-sided surface facing the air and no two walls
share an edge.

    scripts/independent-scenes.py office|hall SEED TARGET_EDGES OUT.json
"""
import json
import math
import random
import sys

from shapely.geometry import Polygon, box, Point
from shapely.geometry.polygon import orient
from shapely import affinity
from shapely.ops import unary_union

WALL = 0.25


def furniture(rng, room, lamps, count):
    """Holes inside `room` (a shapely polygon of free space)."""
    holes = []
    minx, miny, maxx, maxy = room.bounds
    for _ in range(count * 4):
        if len(holes) >= count:
            break
        kind = rng.random()
        cx, cy = rng.uniform(minx, maxx), rng.uniform(miny, maxy)
        if kind < 0.5:
            w, h = rng.uniform(0.4, 1.6), rng.uniform(0.3, 0.9)
            shape = affinity.rotate(box(cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2),
                                    rng.choice([0, 0, 90, rng.uniform(0, 180)]))
        elif kind < 0.8:
            shape = Point(cx, cy).buffer(rng.uniform(0.15, 0.45), quad_segs=rng.choice([2, 3, 4]))
        else:  # an L-shaped desk
            a = box(cx, cy, cx + 1.4, cy + 0.5)
            b = box(cx, cy, cx + 0.5, cy + 1.1)
            shape = affinity.rotate(a.union(b), rng.choice([0, 90, 180, 270]), origin=(cx, cy))
        if not room.buffer(-0.35).contains(shape):
            continue
        if any(shape.buffer(0.3).intersects(o) for o in holes + lamps):
            continue
        holes.append(shape)
    return holes


def office(rng, target):
    # Irregular column widths and row heights; rooms merge into L-shapes now and then.
    n_rooms = max(2, target // 22)
    cols = max(1, round(math.sqrt(n_rooms * 1.3)))
    rows = max(1, math.ceil(n_rooms / cols))
    xs = [0.0]
    for _ in range(cols):
        xs.append(xs[-1] + rng.uniform(3.0, 6.5))
    ys = [0.0]
    for _ in range(rows):
        ys.append(ys[-1] + rng.uniform(3.0, 5.5))
    cells = {}
    for i in range(cols):
        for j in range(rows):
            cells[i, j] = box(xs[i] + WALL / 2, ys[j] + WALL / 2, xs[i + 1] - WALL / 2,
                              ys[j + 1] - WALL / 2)
    # Merge some neighbours into L or long rooms (no wall between them at all).
    pieces = list(cells.values())
    passages = []
    for i in range(cols):
        for j in range(rows):
            for di, dj in [(1, 0), (0, 1)]:
                if (i + di, j + dj) not in cells:
                    continue
                r = rng.random()
                if di == 1:
                    x = xs[i + 1]
                    lo, hi = ys[j] + WALL, ys[j + 1] - WALL
                    if r < 0.12:
                        passages.append(box(x - WALL, lo, x + WALL, hi))
                    elif r < 0.8:
                        d = rng.uniform(0.55, 1.1)
                        c = rng.uniform(lo + d / 2 + 0.1, hi - d / 2 - 0.1)
                        passages.append(box(x - WALL, c - d / 2, x + WALL, c + d / 2))
                else:
                    y = ys[j + 1]
                    lo, hi = xs[i] + WALL, xs[i + 1] - WALL
                    if r < 0.12:
                        passages.append(box(lo, y - WALL, hi, y + WALL))
                    elif r < 0.8:
                        d = rng.uniform(0.55, 1.1)
                        c = rng.uniform(lo + d / 2 + 0.1, hi - d / 2 - 0.1)
                        passages.append(box(c - d / 2, y - WALL, c + d / 2, y + WALL))
    free = unary_union(pieces + passages)
    if free.geom_type != "Polygon":
        free = max(free.geoms, key=lambda g: g.area)
    # Lamps: small emitting squares in a few rooms (one in ten, at least two).
    rooms = list(cells.values())
    rng.shuffle(rooms)
    lamps = []
    for room in rooms[: max(2, len(rooms) // 10)]:
        c = room.centroid
        s = rng.uniform(0.12, 0.25)
        lamps.append(box(c.x - s, c.y - s, c.x + s, c.y + s))
    holes = []
    for room in rooms:
        holes += furniture(rng, room, lamps, rng.randint(0, 4))
    return free, holes, lamps, []


def hall(rng, target):
    n = max(4, target // 5)
    side = math.sqrt(n) * 2.2
    w, h = side * rng.uniform(1.0, 1.6), side
    free = box(0, 0, w, h)
    holes = []
    for _ in range(n * 6):
        if len(holes) >= n:
            break
        cx, cy = rng.uniform(0.5, w - 0.5), rng.uniform(0.5, h - 1.5)
        r = rng.random()
        if r < 0.6:
            a, b = rng.uniform(0.3, 1.3), rng.uniform(0.3, 1.3)
            shape = affinity.rotate(box(cx - a / 2, cy - b / 2, cx + a / 2, cy + b / 2),
                                    rng.uniform(0, 90))
        else:
            shape = Point(cx, cy).buffer(rng.uniform(0.2, 0.5), quad_segs=2)
        if not free.buffer(-0.3).contains(shape):
            continue
        if any(shape.buffer(0.25).intersects(o) for o in holes):
            continue
        holes.append(shape)
    # Skylights: two stretches of the ceiling (the top edge), emitting.
    skylights = []
    for k in range(2):
        x0 = w * (0.2 + 0.5 * k) + rng.uniform(-0.5, 0.5)
        skylights.append((x0, x0 + rng.uniform(0.8, 1.6)))
    return free, holes, [], skylights


def ring_edges(coords, rho, emission=0.0):
    pts = list(coords)[:-1]
    out = []
    for i, a in enumerate(pts):
        b = pts[(i + 1) % len(pts)]
        if math.dist(a, b) < 1e-6:
            continue
        e = {"a": [a[0], a[1]], "b": [b[0], b[1]], "reflectance": rho}
        if emission:
            e["emission"] = emission
        out.append(e)
    return out


def split_skylights(edges, skylights, h):
    """Cuts the top edge (y = h) at the skylights and marks those stretches emitting."""
    out = []
    for e in edges:
        (ax, ay), (bx, by) = e["a"], e["b"]
        if abs(ay - h) > 1e-9 or abs(by - h) > 1e-9:
            out.append(e)
            continue
        cuts = sorted({ax, bx} | {x for s in skylights for x in s if min(ax, bx) < x < max(ax, bx)},
                      reverse=ax > bx)
        for x0, x1 in zip(cuts, cuts[1:]):
            mid = 0.5 * (x0 + x1)
            lit = any(s[0] <= mid <= s[1] for s in skylights)
            piece = {"a": [x0, h], "b": [x1, h], "reflectance": 0.0 if lit else e["reflectance"]}
            if lit:
                piece["emission"] = 5.0
            out.append(piece)
    return out


def main():
    kind, seed, target, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
    rng = random.Random(seed)
    free, holes, lamps, skylights = (office if kind == "office" else hall)(rng, target)
    space = free.difference(unary_union(holes + lamps)) if holes or lamps else free
    if space.geom_type != "Polygon":
        space = max(space.geoms, key=lambda g: g.area)
    space = orient(space, 1.0)  # exterior CCW, holes CW: free space on the left of every edge
    edges = ring_edges(space.exterior.coords, round(rng.uniform(0.5, 0.8), 2))
    if skylights:
        edges = split_skylights(edges, skylights, free.bounds[3])
    lamp_set = [lamp.buffer(1e-9) for lamp in lamps]
    for ring in space.interiors:
        poly = Polygon(ring)
        is_lamp = any(l.contains(poly) for l in lamp_set)
        rho = 0.3 if is_lamp else round(rng.uniform(0.2, 0.9), 2)
        edges += ring_edges(ring.coords, rho, 20.0 if is_lamp else 0.0)
    with open(out, "w") as f:
        json.dump({"edges": edges}, f)
    print(f"{out}: {len(edges)} edges")


if __name__ == "__main__":
    main()
