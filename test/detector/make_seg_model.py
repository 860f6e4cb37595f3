#!/usr/bin/env python3
"""Writes a tiny ONNX graph with the layout of a YOLOv8-seg export, for the
detector's tests and benchmark (no downloaded weights).

Its outputs are constants that encode known candidates and prototypes:
  output0 [1, 4 + nc + nm, N]  box cx, cy, w, h (input px), nc class scores, nm mask coefficients
  output1 [1, nm, H/4, W/4]    mask prototypes
Each constant is added to a zero-weight convolution of the input, so that
OpenCV has to run the graph on every frame instead of folding it away.

Variants (--variant):
  scene       the hand-computed scene of test/core/detector_test.cpp (input 128 x 128, classes
              person, chair, couch, N = 8); see SCENE below
  stock       the size of a stock export (80 classes, 32 prototypes, N anchors of strides 8, 16, 32)
              with random candidates, for the benchmark; --input W H sets imgsz
  one_output  the scene with output1 left out (a detection-only export)
  broadcast   the scene with output0 multiplied by a [1, N] constant of ones, as a stock export
              multiplies its boxes by anchor strides: OpenCV < 4.7 runs it only after
              scripts/onnx_for_opencv.py
Needs Debian's python3-onnx and numpy.
"""
import argparse
import sys

import numpy as np

try:
    import onnx
    from onnx import TensorProto, helper, numpy_helper
except ImportError:  # pragma: no cover - reported to the caller
    sys.exit("make_seg_model.py needs the onnx Python package (Debian: python3-onnx)")

NM = 32  # mask prototypes, as in YOLOv8-seg
L = 10.0  # mask coefficient: sigmoid(10) = 0.99995, sigmoid(-10) = 0.00005

# The scene: (class, confidence, (cx, cy, w, h) in input px, prototype). Prototype 0 is +1
# everywhere (mask = the whole box), prototype 1 is +1 left of input x = 64 and -1 right of it.
SCENE_CLASSES = ["person", "chair", "couch"]
SCENE = [
    ("chair", 0.9, (40, 48, 32, 32), 0),    # A
    ("chair", 0.8, (42, 48, 32, 32), 0),    # duplicate of A (IoU 0.88): suppressed
    ("couch", 0.7, (72, 64, 64, 32), 1),    # B, left half of its box only
    ("couch", 0.6, (44, 48, 32, 32), 0),    # A', overlaps A as much but is of another class: kept
    ("person", 0.95, (100, 100, 20, 20), 0),  # not in the class map
    ("chair", 0.2, (100, 30, 10, 10), 0),   # below conf_threshold
    ("chair", 0.4, (8, 12, 16, 24), 0),     # E, partly in the letterbox padding
    ("person", 0.6, (100, 60, 10, 10), 0),  # chair scores 0.5 too, but its best class is person
]


def scene_outputs():
    nc, n = len(SCENE_CLASSES), len(SCENE)
    out0 = np.zeros((1, 4 + nc + NM, n), np.float32)
    for j, (cls, conf, box, proto) in enumerate(SCENE):
        out0[0, 0:4, j] = box
        out0[0, 4 + SCENE_CLASSES.index(cls), j] = conf
        out0[0, 4 + nc + proto, j] = L
    out0[0, 4 + SCENE_CLASSES.index("chair"), n - 1] = 0.5
    h = w = 128
    protos = np.random.default_rng(0).uniform(-1, 1, (1, NM, h // 4, w // 4)).astype(np.float32)
    protos[0, 0] = 1.0
    protos[0, 1] = -1.0
    protos[0, 1, :, : w // 8] = 1.0  # prototype columns 0..15: input x < 64
    return out0, protos, (w, h)


def stock_outputs(w, h, nc=80, seed=0):
    """Random candidates of a stock-sized export: scores mostly low, a few above 0.25."""
    rng = np.random.default_rng(seed)
    n = sum((w // s) * (h // s) for s in (8, 16, 32))
    out0 = np.zeros((1, 4 + nc + NM, n), np.float32)
    out0[0, 0] = rng.uniform(0, w, n)
    out0[0, 1] = rng.uniform(0, h, n)
    out0[0, 2] = rng.uniform(8, w / 3, n)
    out0[0, 3] = rng.uniform(8, h / 3, n)
    out0[0, 4:4 + nc] = rng.uniform(0, 0.05, (nc, n))
    strong = rng.choice(n, 60, replace=False)  # about as many candidates as a cluttered indoor frame
    out0[0, 4 + rng.integers(0, nc, strong.size), strong] = rng.uniform(0.3, 0.95, strong.size)
    out0[0, 4 + nc:] = rng.normal(0, 1, (NM, n))
    protos = rng.normal(0, 1, (1, NM, h // 4, w // 4)).astype(np.float32)
    return out0, protos


def build(out0, protos, size, one_output=False, broadcast=False):
    w, h = size
    c, n = out0.shape[1], out0.shape[2]
    inits = [
        numpy_helper.from_array(np.zeros((c * n, 3, 1, 1), np.float32), "w0"),
        numpy_helper.from_array(out0.reshape(1, c * n, 1, 1), "c0"),
        numpy_helper.from_array(np.array([1, c, n], np.int64), "shape0"),
        numpy_helper.from_array(np.zeros((NM, 3, 4, 4), np.float32), "w1"),
        numpy_helper.from_array(protos, "c1"),
    ]
    nodes = [
        helper.make_node("GlobalAveragePool", ["images"], ["pooled"]),
        helper.make_node("Conv", ["pooled", "w0"], ["zero0"], kernel_shape=[1, 1]),
        helper.make_node("Add", ["zero0", "c0"], ["flat0"]),
        helper.make_node("Reshape", ["flat0", "shape0"], ["boxes0" if broadcast else "output0"]),
    ]
    if broadcast:
        inits.append(numpy_helper.from_array(np.ones((1, n), np.float32), "strides"))
        nodes.append(helper.make_node("Mul", ["boxes0", "strides"], ["output0"]))
    outputs = [helper.make_tensor_value_info("output0", TensorProto.FLOAT, [1, c, n])]
    if not one_output:
        nodes += [
            helper.make_node("Conv", ["images", "w1"], ["zero1"], kernel_shape=[4, 4], strides=[4, 4]),
            helper.make_node("Add", ["zero1", "c1"], ["output1"]),
        ]
        outputs.append(helper.make_tensor_value_info("output1", TensorProto.FLOAT, [1, NM, h // 4, w // 4]))
    graph = helper.make_graph(nodes, "yolo_seg_test", [helper.make_tensor_value_info(
        "images", TensorProto.FLOAT, [1, 3, h, w])], outputs, inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 12)])
    model.ir_version = 7  # readable by OpenCV 4.6's ONNX importer
    onnx.checker.check_model(model)
    return model


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="ONNX file to write")
    ap.add_argument("--variant", choices=["scene", "stock", "one_output", "broadcast"], default="scene")
    ap.add_argument("--input", nargs=2, type=int, default=[640, 640], metavar=("W", "H"),
                    help="input size of the stock variant, px")
    a = ap.parse_args(argv)
    if a.variant == "stock":
        out0, protos = stock_outputs(*a.input)
        size = tuple(a.input)
    else:
        out0, protos, size = scene_outputs()
    onnx.save(build(out0, protos, size, one_output=a.variant == "one_output", broadcast=a.variant == "broadcast"),
              a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
