#!/usr/bin/env python3
"""Writes anim-rigid.toml (next to this script): 128 rigid instances of three fetched meshes moving
on counter-rotating rings above a ground plane. Deterministic (random.Random(seed)); rerun after
changing the layout: python3 datasets/scenes/bench/make_anim_rigid.py"""
import math
import pathlib
import random

FRAMES, FPS = 60, 30
KEY_FRAMES = [0, 20, 40, 59]
# (mesh file, fit size, count): 12 cows (5,804 triangles), 12 knots (6,400), 104 spheres (320).
MESHES = [("../../cache/meshes/cow.off", 1.1, 12), ("../../cache/meshes/knot1.off", 0.9, 12),
          ("../../cache/meshes/sphere.ply", 0.55, 104)]
RINGS = [1.2, 2.2, 3.2, 4.2, 5.2]  # radii (units)


def main():
    rng = random.Random(39)
    kinds = [m for m in MESHES for _ in range(m[2])]
    rng.shuffle(kinds)
    triangles = {"cow.off": 5804, "knot1.off": 6400, "sphere.ply": 320}
    total = sum(triangles[pathlib.Path(k[0]).name] for k in kinds)
    out = [f"# Bench animation: {len(kinds)} rigid instances of three fetched meshes ({total:,} triangles: 12 cows,",
           "# 12 knots, 104 spheres) on five rings that turn in alternating senses at different speeds, each",
           "# instance spinning about its own axis and bobbing: objects pass each other, so a top-level tree over",
           "# them must change while every object's own tree stays valid. Written by make_anim_rigid.py.",
           "[clip]", f"frames = {FRAMES}", f"fps = {FPS}",
           "[camera]", "eye = [0, 7.5, 8.5]", "target = [0, 0.2, 0]", "fov = 50",
           "[render]", "width = 640", "height = 360", "max_depth = 4",
           "[world]", 'kind = "sky"',
           "[[light]]", 'kind = "directional"', "direction = [-0.4, -1, -0.3]", "intensity = 0.9",
           "[[light]]", 'kind = "point"', "position = [3, 6, 3]", "intensity = 0.5",
           "[[material]]", 'name = "clay"', "color = [0.85, 0.8, 0.7]", "specular = 0.2",
           "[[material]]", 'name = "ground"', "color = [0.55, 0.55, 0.55]",
           "[[object]]", 'kind = "plane"', 'material = "ground"', "scale = 8"]
    per_ring = [int(len(kinds) * r / sum(RINGS)) for r in RINGS]
    per_ring[-1] += len(kinds) - sum(per_ring)
    i = 0
    for ring, (radius, count) in enumerate(zip(RINGS, per_ring)):
        sense = 1 if ring % 2 == 0 else -1
        turn = sense * rng.uniform(50, 80) / (radius ** 0.5)  # degrees of the ring per key segment
        for j in range(count):
            mesh, fit, _ = kinds[i]
            i += 1
            phase = 360.0 * (j + rng.uniform(-0.2, 0.2)) / count
            r = radius + rng.uniform(-0.25, 0.25)
            axis = [rng.uniform(-1, 1), rng.uniform(0.3, 1), rng.uniform(-1, 1)]
            spin = rng.uniform(40, 110) * rng.choice([-1, 1])  # degrees per key segment (< 180: slerp's short arc)
            bob = rng.uniform(0.0, 0.4)
            out += ["[[object]]", 'kind = "mesh"', f'name = "r{ring}_{j}"', f'mesh = "{mesh}"', 'material = "clay"',
                    f"fit = {fit}"]
            for k, f in enumerate(KEY_FRAMES):
                a = math.radians(phase + turn * k)
                y = 0.05 + bob * (0.5 + 0.5 * math.sin(k * 2.1 + j))
                out += ["[[object.keys]]", f"frame = {f}",
                        f"position = [{r * math.cos(a):.4f}, {y:.4f}, {r * math.sin(a):.4f}]",
                        f"rotation = {{ axis = [{axis[0]:.3f}, {axis[1]:.3f}, {axis[2]:.3f}], angle = {spin * k:.2f} }}"]
    path = pathlib.Path(__file__).with_name("anim-rigid.toml")
    path.write_text("\n".join(out) + "\n")
    print(f"{path}: {len(kinds)} instances, {total} triangles")


if __name__ == "__main__":
    main()
