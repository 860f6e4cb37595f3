#!/usr/bin/env python3
"""Generates a furnished indoor scene in Habitat/Matterport layout and, optionally, its ground truth.

Example:
  generate_scene.py --seed 3 --size 15 12 3 --out /tmp/scenes   # -> gen_s3_15x12_semantic.ply, .house
  generate_scene.py --seed 3 --size 8 6 3 --out /tmp/s --gt /tmp/s/gt
  generate_scene.py --layout three_chairs --out test/data   # the fixed test room (three_chairs_semantic.ply)
"""
import argparse
import os
import sys


def _import_package():
    try:
        import semantic_exploration.sim  # noqa: F401
    except ImportError:  # running from the source tree
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src"))


def main(argv=None):
    _import_package()
    from semantic_exploration.sim.classes import DEFAULT_CLASS_NAMES
    from semantic_exploration.sim.generator import generate, three_chairs_room
    from semantic_exploration.sim.scene import export_ground_truth, save_habitat
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--size", type=float, nargs=3, default=[15.0, 12.0, 3.0], metavar=("X", "Y", "H"),
                    help="house size, m")
    ap.add_argument("--layout", choices=("house", "three_chairs"), default="house",
                    help="house: generated from seed and size; three_chairs: the fixed test room (seed: colours)")
    ap.add_argument("--name", default=None, help="scene name (default gen_s<seed>_<X>x<Y>)")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--gt", default=None, help="also export ground truth into this directory")
    ap.add_argument("--free-resolution", type=float, default=0.1, help="free-space grid voxel size, m")
    a = ap.parse_args(argv)
    if a.layout == "three_chairs":
        scene = three_chairs_room(a.seed, a.name or "three_chairs")
    else:
        scene = generate(a.seed, a.size, a.name)
    ply = save_habitat(scene, a.out)
    print(ply)
    if a.gt:
        doc = export_ground_truth(scene, a.gt, DEFAULT_CLASS_NAMES, a.free_resolution)
        print("%s: %d objects" % (os.path.join(a.gt, "objects.json"), len(doc["objects"])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
