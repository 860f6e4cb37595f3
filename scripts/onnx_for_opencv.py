#!/usr/bin/env python3
"""Prepares a YOLOv8-seg / YOLO11-seg ONNX export for the detector node.

OpenCV before 4.7 (Debian 12 ships 4.6) cannot broadcast an element-wise
operation between a tensor and a constant of another shape other than a
scalar: a stock export multiplies its [1, 4, N] boxes by a [1, N] constant of
anchor strides, and OpenCV stops with "start <= (int)shape.size()" in
shape_utils.hpp. This script writes each such constant out at the full shape
of the other operand (values unchanged, so the network computes the same),
then prints the model's input size, class count and candidate count with the
`detector/input_size` to set. Needs Debian's python3-onnx.

  scripts/onnx_for_opencv.py yolov8n-seg.onnx yolov8n-seg-opencv.onnx
"""
import argparse
import sys

import numpy as np

try:
    import onnx
    from onnx import numpy_helper, shape_inference
except ImportError:
    sys.exit("onnx_for_opencv.py needs the onnx Python package (Debian: python3-onnx)")

ELEMENTWISE = ("Add", "Sub", "Mul", "Div")


def _dims(value_info):
    return [d.dim_value if d.HasField("dim_value") else 0 for d in value_info.type.tensor_type.shape.dim]


def expand_broadcast_constants(model):
    """Expands constant operands of Add/Sub/Mul/Div that need broadcasting
    (more than one element, shape unlike the other operand's) to that shape.
    Returns [(node name, old shape, new shape)]."""
    inferred = shape_inference.infer_shapes(model)
    shapes = {vi.name: _dims(vi) for vi in list(inferred.graph.value_info) + list(inferred.graph.input) +
              list(inferred.graph.output)}
    graph = model.graph
    tensors = {t.name: t for t in graph.initializer}  # constant tensors by output name
    for node in graph.node:
        if node.op_type == "Constant":
            for a in node.attribute:
                if a.name == "value":
                    tensors[node.output[0]] = a.t
    changed = []
    for node in graph.node:
        if node.op_type not in ELEMENTWISE or len(node.input) != 2:
            continue
        for k in (0, 1):
            const, other = node.input[k], node.input[1 - k]
            if const not in tensors or other in tensors:
                continue
            target = shapes.get(other)
            value = numpy_helper.to_array(tensors[const])
            if value.size <= 1 or not target or 0 in target or list(value.shape) == target:
                continue
            full = np.ascontiguousarray(np.broadcast_to(value, target)).astype(value.dtype)
            tensors[const].CopyFrom(numpy_helper.from_array(full, tensors[const].name))
            changed.append((node.name, list(value.shape), target))
    return changed


def describe(model):
    """(input [W, H], output shapes) of a model, from shape inference."""
    inferred = shape_inference.infer_shapes(model)
    inp = _dims(inferred.graph.input[0])
    return inp, [(o.name, _dims(o)) for o in inferred.graph.output]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("model", help="ONNX export (yolo export ... format=onnx opset=12)")
    ap.add_argument("out", help="ONNX file to write")
    a = ap.parse_args(argv)
    model = onnx.load(a.model)
    for name, old, new in expand_broadcast_constants(model):
        print("expanded the constant of %s from %s to %s" % (name, old, new))
    onnx.save(model, a.out)
    inp, outs = describe(model)
    print("input %s, outputs %s" % (inp, ", ".join("%s %s" % o for o in outs)))
    if len(inp) == 4 and len(outs) == 2:
        o0 = next((s for _, s in outs if len(s) == 3), None)
        o1 = next((s for _, s in outs if len(s) == 4), None)
        if o0 and o1:
            print("%d classes, %d candidates; set detector/input_size: [%d, %d]" % (
                o0[1] - 4 - o1[1], o0[2], inp[3], inp[2]))
            return 0
    print("warning: not the YOLOv8-seg layout (input [1, 3, H, W], output0 [1, 4 + nc + 32, N], "
          "output1 [1, 32, H/4, W/4])", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
