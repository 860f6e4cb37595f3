// The map-block codec (core/map_blocks.hpp): int8 log-odds x 10, worked by hand.
#include <gtest/gtest.h>

#include <cstdint>

#include "semantic_exploration/core/map_blocks.hpp"

using namespace semexp;

TEST(MapBlocksCodec, EncodesThousandthsAsTenthsKeepingTheSign) {
  EXPECT_EQ(map_blocks::encodeMilli(INT16_MIN), -128);  // unknown
  EXPECT_EQ(map_blocks::encodeMilli(850), 9);           // 0.85 -> 8.5 -> 9 (half away from zero)
  EXPECT_EQ(map_blocks::encodeMilli(-2000), -20);
  EXPECT_EQ(map_blocks::encodeMilli(-40), -1);          // -0.04 would round to 0 (occupied): kept free
  EXPECT_EQ(map_blocks::encodeMilli(0), 0);
  EXPECT_EQ(map_blocks::encodeMilli(30000), 127);       // clamped
  EXPECT_EQ(map_blocks::encodeMilli(-30000), -127);     // -128 stays reserved for unknown
  EXPECT_EQ(map_blocks::decodeMilli(-1), -100);
  EXPECT_EQ(map_blocks::decodeMilli(9), 900);
  EXPECT_EQ(map_blocks::decodeMilli(-128), INT16_MIN);
}

TEST(MapBlocksCodec, StateOfAnEncodedVoxel) {
  EXPECT_EQ(map_blocks::stateOf(-128), VoxelState::kUnknown);
  EXPECT_EQ(map_blocks::stateOf(-1), VoxelState::kFree);
  EXPECT_EQ(map_blocks::stateOf(0), VoxelState::kOccupied);
  EXPECT_EQ(map_blocks::stateOf(5, 10), VoxelState::kFree);  // a stricter free threshold
  EXPECT_EQ(map_blocks::stateOf(10, 10), VoxelState::kOccupied);
}
