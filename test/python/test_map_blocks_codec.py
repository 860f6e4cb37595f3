"""The Python map-block codec (semantic_exploration/map_blocks.py) against the C++ side.

test/tools/map_blocks_dump builds a background map of a box room seen from two poses
and writes its full and compact snapshots as background_map sends them
(toMapBlocksMsg, roscpp serialisation), plus the C++ map's own code at 20000 random
voxel centres. Decoding those bytes here must give the same code at every probe; a
decoder with the axes of a block swapped gives thousands of different ones (checked, so
the scene cannot hide a layout error). Skipped where ROS is not sourced."""
import os
import shutil
import subprocess

import numpy as np
import pytest

from semantic_exploration import map_blocks

from installed import installed_tool  # noqa: E402

ROS_SOURCED = shutil.which("roslaunch") is not None and "CMAKE_PREFIX_PATH" in os.environ


def dump_tool():
    return installed_tool("map_blocks_dump")


@pytest.fixture(scope="module")
def dumped(tmp_path_factory):
    if not ROS_SOURCED:
        pytest.skip("ROS is not sourced")
    from semantic_exploration.msg import MapBlocks
    out = tmp_path_factory.mktemp("map_blocks")
    subprocess.run([dump_tool(), str(out)], check=True, timeout=120)
    msgs = {}
    for name in ("full", "compact"):
        with open(str(out / (name + ".bin")), "rb") as f:
            msgs[name] = MapBlocks().deserialize(f.read())
    probes = np.loadtxt(str(out / "probes.txt"))
    return msgs, probes[:, :3], probes[:, 3].astype(int)


def mismatches(decoded, points, codes):
    return sum(decoded.value(p) != c for p, c in zip(points, codes))


@pytest.mark.parametrize("name", ["full", "compact"])
def test_decodes_the_cpp_snapshot_to_the_cpp_map(dumped, name):
    msgs, points, codes = dumped
    m = msgs[name]
    assert m.header.frame_id == "world" and m.header.stamp.to_sec() == 12.5
    if name == "compact":
        assert len(m.uniform_values) > 10 and len(m.coords) < len(msgs["full"].coords)
    else:
        assert len(m.uniform_values) == 0
    decoded = map_blocks.decode(m)
    # The probes hold every state, so the comparison below covers each.
    states = [map_blocks.state_of(c) for c in codes]
    assert states.count(map_blocks.FREE) > 2000
    assert states.count(map_blocks.OCCUPIED) > 20
    assert states.count(map_blocks.UNKNOWN) > 2000
    assert mismatches(decoded, points, codes) == 0


def test_a_wrong_block_layout_is_caught_by_the_probes(dumped):
    msgs, points, codes = dumped
    decoded = map_blocks.decode(msgs["full"])
    for k in decoded.blocks:
        decoded.blocks[k] = decoded.blocks[k].transpose(2, 1, 0)  # z fastest instead of x
    assert mismatches(decoded, points, codes) > 100


def test_encoding_matches_the_header_on_hand_computed_values():
    # log-odds x 10, halves away from 0, clamped to +-127; a negative log-odds stays negative; NaN = unknown
    l = [-0.04, 0.04, 0.05, -0.05, -0.15, 1.0, 12.7, 13.0, -13.0, float("nan")]
    q = [-1, 0, 1, -1, -2, 10, 127, 127, -127, -128]
    assert map_blocks.encode_log_odds(l).tolist() == q
    back = map_blocks.decode_log_odds(q)
    assert back[5] == 1.0 and back[4] == pytest.approx(-0.2) and np.isnan(back[-1])
    assert [map_blocks.state_of(v) for v in (-1, 0, -128)] == [map_blocks.FREE, map_blocks.OCCUPIED,
                                                               map_blocks.UNKNOWN]


def test_encode_writes_x_fastest_blocks_that_decode_back():
    if not ROS_SOURCED:
        pytest.skip("ROS is not sourced")
    from semantic_exploration.msg import MapBlocks
    g = np.full((16, 8, 8), -4, dtype=np.int8)
    g[9, 2, 5] = 55  # block (1, 0, 0), voxel (1, 2, 5) within it
    m = map_blocks.encode(MapBlocks(), g, (-1.0, 0.0, 0.5), 0.1, 8, sequence=3, full=True)
    assert list(m.coords) == [0, 0, 0, 1, 0, 0]
    payload = np.frombuffer(bytes(m.payload), dtype=np.int8)
    assert payload.size == 2 * 512
    assert payload[512 + (5 * 8 + 2) * 8 + 1] == 55 and np.count_nonzero(payload == 55) == 1
    d = map_blocks.decode(MapBlocks().deserialize(serialised(m)))
    assert d.value((-1.0 + 0.95, 0.25, 0.5 + 0.55)) == 55  # centre of voxel (9, 2, 5)
    assert d.value((-1.0 + 0.85, 0.25, 0.5 + 0.55)) == -4
    assert d.value((-1.05, 0.25, 0.55)) == map_blocks.UNKNOWN_I8  # voxel x = -1: no block
    m.encoding = 9
    with pytest.raises(map_blocks.MapBlocksError, match="encoding 9"):
        map_blocks.decode(m)
    m.encoding = 0
    m.payload = m.payload[:-1]
    with pytest.raises(map_blocks.MapBlocksError, match="disagree"):
        map_blocks.decode(m)


def serialised(msg):
    import io
    buf = io.BytesIO()
    msg.serialize(buf)
    return buf.getvalue()
