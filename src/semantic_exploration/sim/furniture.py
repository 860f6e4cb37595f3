"""Generated furniture, built from boxes, cylinders and spheres so that each class is recognisable
at 2 cm: chairs, armchairs, tables, sofas with cushions, beds, cabinets, plants, monitors/TVs,
keyboards and backpacks."""

from .mesh_builder import MeshBuilder, vary_colour


# ---------------------------------------------------------------------------
# Furniture, each in its local frame: origin on the floor at the footprint
# centre, front towards +x. Returns the footprint half extents (hx, hy).
# ---------------------------------------------------------------------------
WOODS = [(139, 94, 60), (160, 120, 80), (110, 75, 45), (190, 160, 120), (90, 60, 40)]
FABRICS = [(70, 90, 140), (150, 60, 60), (90, 130, 90), (120, 120, 120), (180, 150, 100), (60, 60, 70)]


def chair(b: MeshBuilder, pose, z0=0.0):
    rng = b.rng
    oid = b.new_object("chair")
    wood = vary_colour(rng, WOODS[rng.integers(len(WOODS))])
    seat = vary_colour(rng, FABRICS[rng.integers(len(FABRICS))])
    w, d, h = 0.44, 0.44, 0.45
    for sx in (-1, 1):
        for sy in (-1, 1):
            b.box(oid, wood, (sx * (d / 2 - 0.03), sy * (w / 2 - 0.03), z0 + h / 2), (0.035, 0.035, h), pose)
    b.box(oid, seat, (0, 0, z0 + h + 0.025), (d, w, 0.05), pose)
    b.box(oid, wood, (-d / 2 + 0.02, 0, z0 + h + 0.05 + 0.22), (0.035, w, 0.36), pose)  # backrest
    return oid, (d / 2, w / 2)


def armchair(b: MeshBuilder, pose):
    rng = b.rng
    oid = b.new_object("chair")
    fab = vary_colour(rng, FABRICS[rng.integers(len(FABRICS))])
    b.box_minmax(oid, fab, (-0.38, -0.38, 0.0), (0.38, 0.38, 0.42), pose)
    b.box_minmax(oid, fab, (-0.38, -0.38, 0.42), (-0.2, 0.38, 0.9), pose)
    for sy in (-1, 1):
        b.box_minmax(oid, vary_colour(rng, fab, 8), (-0.2, sy * 0.38 - 0.07, 0.42),
                     (0.38, sy * 0.38 + 0.07, 0.62), pose)
    return oid, (0.38, 0.45)


def table(b: MeshBuilder, pose, length=1.4, width=0.85, height=0.75, label="table"):
    rng = b.rng
    oid = b.new_object(label)
    wood = vary_colour(rng, WOODS[rng.integers(len(WOODS))])
    b.box(oid, wood, (0, 0, height - 0.02), (width, length, 0.04), pose)
    for sx in (-1, 1):
        for sy in (-1, 1):
            b.box(oid, vary_colour(rng, wood, 6),
                  (sx * (width / 2 - 0.06), sy * (length / 2 - 0.06), (height - 0.04) / 2),
                  (0.05, 0.05, height - 0.04), pose)
    return oid, (width / 2, length / 2)


def sofa(b: MeshBuilder, pose, length=2.0):
    rng = b.rng
    oid = b.new_object("sofa")
    fab = vary_colour(rng, FABRICS[rng.integers(len(FABRICS))])
    d = 0.88
    b.box_minmax(oid, vary_colour(rng, fab, 5), (-d / 2, -length / 2, 0.08), (d / 2, length / 2, 0.42), pose)
    b.box_minmax(oid, fab, (-d / 2, -length / 2 + 0.18, 0.42), (-d / 2 + 0.22, length / 2 - 0.18, 0.86), pose)
    for sy in (-1, 1):
        y0 = sy * length / 2
        b.box_minmax(oid, fab, (-d / 2, min(y0, y0 - sy * 0.18), 0.08), (d / 2, max(y0, y0 - sy * 0.18), 0.64), pose)
        for sx in (-1, 1):  # feet
            b.box(oid, (40, 30, 25), (sx * (d / 2 - 0.06), y0 - sy * 0.06, 0.04), (0.05, 0.05, 0.08), pose)
    return oid, (d / 2, length / 2)


def cushion(b: MeshBuilder, pose, z0):
    rng = b.rng
    oid = b.new_object("cushion")
    col = vary_colour(rng, FABRICS[rng.integers(len(FABRICS))], 30)
    # Soft look: a flattened sphere over a thin box.
    b.box(oid, col, (0, 0, z0 + 0.04), (0.12, 0.38, 0.08), pose)
    b.sphere(oid, col, (0, 0, z0 + 0.2), (0.07, 0.2, 0.19), pose)
    return oid, (0.1, 0.21)


def bed(b: MeshBuilder, pose, width=1.5, length=2.05):
    rng = b.rng
    oid = b.new_object("bed")
    wood = vary_colour(rng, WOODS[rng.integers(len(WOODS))])
    sheet = vary_colour(rng, (225, 225, 215), 10)
    b.box_minmax(oid, wood, (-length / 2, -width / 2, 0.05), (length / 2, width / 2, 0.32), pose)
    b.box_minmax(oid, sheet, (-length / 2 + 0.08, -width / 2 + 0.04, 0.32), (length / 2 - 0.03, width / 2 - 0.04, 0.52),
                 pose)
    b.box_minmax(oid, wood, (-length / 2, -width / 2, 0.0), (-length / 2 + 0.08, width / 2, 1.05), pose)  # headboard
    for sy in (-1, 1):
        b.box(oid, (245, 245, 240), (-length / 2 + 0.3, sy * width / 4, 0.58), (0.35, width / 2 - 0.15, 0.12), pose)
    return oid, (length / 2, width / 2)


def cabinet(b: MeshBuilder, pose, width=0.9, depth=0.45, height=0.8):
    rng = b.rng
    oid = b.new_object("cabinet")
    wood = vary_colour(rng, WOODS[rng.integers(len(WOODS))])
    b.box_minmax(oid, vary_colour(rng, wood, 5), (-depth / 2, -width / 2, 0.0), (depth / 2, width / 2, 0.06), pose)
    b.box_minmax(oid, wood, (-depth / 2, -width / 2, 0.06), (depth / 2 - 0.02, width / 2, height), pose)
    n_doors = 2 if width > 0.6 else 1
    for k in range(n_doors):
        yc = -width / 2 + (k + 0.5) * width / n_doors
        b.box(oid, vary_colour(rng, wood, 12), (depth / 2 - 0.01, yc, (height + 0.06) / 2),
              (0.02, width / n_doors - 0.02, height - 0.1), pose)
        b.box(oid, (200, 200, 205), (depth / 2 + 0.01, yc + (0.08 if k == 0 and n_doors == 2 else -0.08),
                                     height * 0.6), (0.02, 0.02, 0.12), pose)
    return oid, (depth / 2, width / 2), height


def plant(b: MeshBuilder, pose):
    rng = b.rng
    oid = b.new_object("plant")
    pot = vary_colour(rng, (180, 90, 60), 12)
    b.cylinder(oid, pot, (0, 0, 0), 0.16, 0.32, pose)
    b.cylinder(oid, (90, 70, 40), (0, 0, 0.32), 0.02, 0.45, pose)
    for _ in range(int(rng.integers(4, 7))):
        c = (rng.uniform(-0.12, 0.12), rng.uniform(-0.12, 0.12), rng.uniform(0.65, 1.05))
        r = rng.uniform(0.12, 0.2)
        b.sphere(oid, vary_colour(rng, (50, 120, 50), 25), c, (r, r, r * 0.8), pose)
    return oid, (0.3, 0.3)


def monitor(b: MeshBuilder, pose, z0, big=False):
    rng = b.rng
    oid = b.new_object("tv_monitor")
    w, h = (1.0, 0.6) if big else (0.56, 0.34)
    frame = vary_colour(rng, (35, 35, 38), 6)
    b.box(oid, frame, (0, 0, z0 + 0.012), (0.2, 0.28, 0.025), pose)  # foot
    b.box(oid, frame, (-0.03, 0, z0 + 0.1), (0.04, 0.05, 0.16), pose)  # neck
    b.box(oid, frame, (0, 0, z0 + 0.16 + h / 2), (0.04, w, h), pose)  # panel
    b.box(oid, (20, 25, 45), (0.021, 0, z0 + 0.16 + h / 2), (0.004, w - 0.04, h - 0.04), pose)  # screen
    return oid, (0.1, w / 2)


def keyboard(b: MeshBuilder, pose, z0):
    oid = b.new_object("keyboard")
    col = vary_colour(b.rng, (50, 50, 55), 10)
    b.box(oid, col, (0, 0, z0 + 0.012), (0.15, 0.44, 0.024), pose)
    for r in range(4):
        b.box(oid, (200, 200, 200), (-0.05 + r * 0.033, 0, z0 + 0.028), (0.022, 0.40, 0.008), pose)
    return oid, (0.075, 0.22)


def backpack(b: MeshBuilder, pose, z0=0.0):
    rng = b.rng
    oid = b.new_object("backpack")
    col = vary_colour(rng, [(200, 60, 40), (40, 80, 160), (60, 60, 60), (50, 120, 70)][rng.integers(4)], 15)
    b.box(oid, col, (0, 0, z0 + 0.21), (0.18, 0.3, 0.42), pose)
    b.cylinder(oid, col, (0, 0, z0 + 0.42), 0.09, 0.05, (pose[0], pose[1], pose[2]) if pose else None)
    b.box(oid, vary_colour(rng, col, 20), (0.11, 0, z0 + 0.14), (0.06, 0.24, 0.2), pose)  # front pocket
    for sy in (-1, 1):
        b.box(oid, (30, 30, 30), (-0.1, sy * 0.09, z0 + 0.25), (0.02, 0.04, 0.34), pose)  # straps
    return oid, (0.14, 0.16)
