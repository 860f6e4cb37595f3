// The pieces that keep bled masks out of object maps: depth edges within a
// mask, the gap between two masks' surfaces, mask pixels of unknown
// membership in the TSDF update, less foreground evidence at a mask's border,
// dropping the part of a map beyond a plane, and stray mesh fragments.

#include <gtest/gtest.h>

#include "semantic_exploration/core/object_masks.hpp"
#include "semantic_exploration/core/object_mesh.hpp"
#include "semantic_exploration/core/tsdf.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/rendering.hpp"

using namespace semexp;
using namespace semexp_test;

namespace {

constexpr std::uint8_t kUnknown = TsdfMap::kMaskUnknown;

TEST(ObjectMasks, PixelsBehindADepthEdgeWithinTheWindowAreMarked) {
  PinholeCamera cam;
  // Columns < 120 at 1.5 m, the rest at 2.5 m; the mask spans columns 100 .. 139 over the full height.
  cv::Mat depth(cam.height, cam.width, CV_32FC1, cv::Scalar(2.5f));
  depth.colRange(0, 120).setTo(1.5f);
  cv::Mat mask = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  mask.colRange(100, 140).setTo(255);
  DepthEdgeParams p;  // 0.3 m + 5% of 1.5 m, 8 px
  const int marked = markDepthEdges(mask, depth, cam, p, kUnknown);
  // The far pixels up to 8 columns from the edge (120 .. 127), every row; nothing else.
  EXPECT_EQ(marked, 8 * cam.height);
  EXPECT_EQ(cv::countNonZero(mask.colRange(120, 128) == kUnknown), 8 * cam.height);
  EXPECT_EQ(cv::countNonZero(mask == kUnknown), 8 * cam.height);
  EXPECT_EQ(cv::countNonZero(mask == 255), 32 * cam.height);
  // Farther than the threshold only: a step of 0.3 m is no edge.
  depth.colRange(120, cam.width).setTo(1.8f);
  mask.colRange(100, 140).setTo(255);
  EXPECT_EQ(markDepthEdges(mask, depth, cam, p, kUnknown), 0);
  // Off with a window of 0.
  p.window_px = 0;
  depth.colRange(120, cam.width).setTo(2.5f);
  EXPECT_EQ(markDepthEdges(mask, depth, cam, p, kUnknown), 0);
  EXPECT_THROW(markDepthEdges(mask, cv::Mat::zeros(10, 10, CV_32FC1), cam, p, kUnknown), std::invalid_argument);
}

TEST(ObjectMasks, DepthNoiseAloneMakesNoEdge) {
  PinholeCamera cam;
  // One plane at 2 m with 8 cm of noise (about 5x the simulator's at 2 m): single pixels lie up to 0.4 m
  // behind their neighbours, the 5 x 5 medians do not.
  cv::Mat noise(cam.height, cam.width, CV_32FC1);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.08);
  const cv::Mat depth = noise + 2.0f;
  cv::Mat mask = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  mask(cv::Rect(60, 40, 200, 160)).setTo(255);
  DepthEdgeParams p;
  p.edge_m = 0.3;
  p.edge_rel = 0.0;
  EXPECT_EQ(markDepthEdges(mask, depth, cam, p, kUnknown), 0);
}

TEST(ObjectMasks, GapBetweenTwoMasksSurfaces) {
  PinholeCamera cam;
  const cv::Mat depth(cam.height, cam.width, CV_32FC1, cv::Scalar(2.0f));
  cv::Mat a = cv::Mat::zeros(cam.height, cam.width, CV_8UC1), b = a.clone();
  a(cv::Rect(100, 80, 40, 80)).setTo(255);  // columns 100 .. 139
  b(cv::Rect(150, 80, 40, 80)).setTo(255);  // columns 150 .. 189
  // x = (u - cx) z / fx: the last 2% of a's points lie in column 139, the first 2% of b's in column 150.
  const double px_m = 2.0 / cam.fx;
  MaskSeparation s = separateMasks(a, b, depth, cam);
  EXPECT_NEAR(s.gap_m, 11 * px_m, 1e-4);
  EXPECT_NEAR(s.normal_C.x(), 1.0, 1e-6);
  EXPECT_NEAR(s.plane_m, (144.5 - cam.cx) * px_m, 1e-4);
  // Touching masks (columns 100 .. 139 and 140 .. 179): one pixel apart.
  b.setTo(0);
  b(cv::Rect(140, 80, 40, 80)).setTo(255);
  EXPECT_NEAR(separateMasks(a, b, depth, cam).gap_m, px_m, 1e-4);
  // Marked (unknown) pixels do not count; too few points: NaN.
  b.setTo(kUnknown, b);
  EXPECT_TRUE(std::isnan(separateMasks(a, b, depth, cam).gap_m));
}

TsdfParams params() {
  TsdfParams p;
  p.resolution_m = 0.02;
  p.truncation_m = 0.08;
  return p;
}

const Sphere kSphere(Eigen::Vector3d(0.0, 0.0, 1.0), 0.25);

TEST(ObjectMasks, UnknownMaskPixelsNeitherFillNorCarve) {
  PinholeCamera cam;
  const auto T_WC = lookAt(Eigen::Vector3d(-1.0, 0.0, 1.0), kSphere.centre);
  cv::Mat depth, labels;
  renderShapes(cam, T_WC, {&kSphere}, depth, labels);
  TsdfMap map(params());
  const cv::Mat unknown(cam.height, cam.width, CV_8UC1, cv::Scalar(kUnknown));
  EXPECT_EQ(map.integrate(cam, T_WC, depth, cv::Mat(), unknown, true), 0u);
  EXPECT_EQ(map.blockCount(), 0u);
  // Seen as the object once, then through masks of unknown pixels: the foreground stays; outside the mask
  // (0) it falls.
  map.integrate(cam, T_WC, depth, cv::Mat(), labels == 1, true);
  const size_t surface = map.summarize(1.0).voxel_count;
  ASSERT_GT(surface, 500u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(map.integrate(cam, T_WC, depth, cv::Mat(), unknown, true), 0u);
  EXPECT_EQ(map.summarize(1.0).voxel_count, surface);
  map.integrate(cam, T_WC, depth, cv::Mat(), cv::Mat::zeros(cam.height, cam.width, CV_8UC1), true);
  EXPECT_EQ(map.summarize(1.0).voxel_count, 0u);
}

TEST(ObjectMasks, BorderPixelsGetLessForegroundEvidence) {
  // A 20 x 20 px detection, 3 px border: chessboard rings k = 1, 2, 3 get 128 + round(127 k / 4) = 160, 192,
  // 223 (evidence 0.626, 0.752, 0.878); the 14 x 14 px inside keeps 255.
  cv::Mat detected = cv::Mat::zeros(30, 40, CV_8UC1);
  detected(cv::Rect(10, 5, 20, 20)).setTo(255);
  cv::Mat mask = detected.clone();
  mask.at<std::uint8_t>(15, 20) = 0;         // taken from the mask (another object's pixel): stays out
  mask.at<std::uint8_t>(15, 21) = kUnknown;  // behind a depth edge: stays unknown
  EXPECT_EQ(markMaskBorder(mask, detected, 3), 76 + 68 + 60);
  EXPECT_EQ(cv::countNonZero(mask == 160), 76);
  EXPECT_EQ(cv::countNonZero(mask == 192), 68);
  EXPECT_EQ(cv::countNonZero(mask == 223), 60);
  EXPECT_EQ(cv::countNonZero(mask == 255), 14 * 14 - 2);
  EXPECT_EQ(mask.at<std::uint8_t>(15, 20), 0);
  EXPECT_EQ(mask.at<std::uint8_t>(15, 21), kUnknown);
  EXPECT_EQ(mask.at<std::uint8_t>(15, 19), 255);  // the pixel taken out is no border: distances are the detection's
  EXPECT_NEAR(TsdfMap::maskEvidence(160), 0.5 + 0.5 * 32 / 127.0, 1e-6);
  EXPECT_EQ(TsdfMap::maskEvidence(255), 1.f);
  EXPECT_EQ(TsdfMap::maskEvidence(1), 1.f);

  // A detection cut by the image's left edge did not bleed there: column 0 is no border, the right side is.
  detected.setTo(0);
  detected(cv::Rect(0, 5, 10, 20)).setTo(255);
  mask = detected.clone();
  markMaskBorder(mask, detected, 3);
  EXPECT_EQ(mask.at<std::uint8_t>(15, 0), 255);
  EXPECT_EQ(mask.at<std::uint8_t>(15, 9), 160);
  EXPECT_EQ(mask.at<std::uint8_t>(15, 7), 223);
  EXPECT_EQ(mask.at<std::uint8_t>(5, 0), 160);  // the top row is a border

  // Off with 0 px; bad input throws.
  cv::Mat same = detected.clone();
  EXPECT_EQ(markMaskBorder(same, detected, 0), 0);
  EXPECT_EQ(cv::countNonZero(same != detected), 0);
  EXPECT_THROW(markMaskBorder(same, detected, 127), std::invalid_argument);
  EXPECT_THROW(markMaskBorder(same, cv::Mat::zeros(10, 10, CV_8UC1), 3), std::invalid_argument);
}

TEST(ObjectMasks, BorderMaskValuesRaiseTheForegroundByTheirEvidence) {
  PinholeCamera cam;
  const auto T_WC = lookAt(Eigen::Vector3d(-1.0, 0.0, 1.0), kSphere.centre);
  cv::Mat depth, labels;
  renderShapes(cam, T_WC, {&kSphere}, depth, labels);
  // The voxel on the sphere's near pole (-0.25, 0, 1), first seen through a mask of value v: its foreground is
  // v's evidence (a first observation of weight 1 against weight 0), 1 for 255 and for the legacy 1.
  const Eigen::Vector3i pole(-13, 0, 50);  // centre (-0.25, 0.01, 1.01): on the surface (0.4 mm outside)
  for (const std::uint8_t v : {std::uint8_t{160}, std::uint8_t{200}, std::uint8_t{255}, std::uint8_t{1}}) {
    TsdfMap map(params());
    cv::Mat mask = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
    mask.setTo(v, labels == 1);
    map.integrate(cam, T_WC, depth, cv::Mat(), mask, true);
    const TsdfVoxel* vx = map.voxel(pole);
    ASSERT_NE(vx, nullptr);
    EXPECT_NEAR(vx->weight(), 1.f, 1e-3f);
    EXPECT_NEAR(vx->foreground(), TsdfMap::maskEvidence(v), 0.5 / 254) << "mask value " << int{v};
  }
}

// A triangle of edge `size` with its first corner at `at`, appended to `mesh`.
void addTriangle(Mesh& mesh, const Eigen::Vector3f& at, float size) {
  const auto i = static_cast<std::uint32_t>(mesh.vertices_W.size());
  mesh.vertices_W.insert(mesh.vertices_W.end(), {at, at + Eigen::Vector3f(size, 0, 0), at + Eigen::Vector3f(0, size, 0)});
  mesh.colours.insert(mesh.colours.end(), 3, {{10, 20, 30}});
  mesh.triangles.push_back({i, i + 1, i + 2});
}

TEST(ObjectMasks, MeshFragmentsFarFromTheObjectAreDropped) {
  // The body: two triangles sharing an edge (4 vertices). A piece 0.2 m from it (kept, 0.3 m gap), a piece
  // 0.25 m beyond that one (kept through it), and one 1 m away (dropped).
  Mesh mesh;
  mesh.vertices_W = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}, {0.1f, 0.1f, 0}};
  mesh.colours.assign(4, {{1, 2, 3}});
  mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
  addTriangle(mesh, Eigen::Vector3f(0.3f, 0, 0), 0.01f);   // 0.2 m from (0.1, 0, 0)
  addTriangle(mesh, Eigen::Vector3f(0.56f, 0, 0), 0.01f);  // 0.25 m from the piece before
  addTriangle(mesh, Eigen::Vector3f(1.1f, 0.1f, 0), 0.01f);  // 1 m from the body, 0.53 m from the last kept
  Mesh copy = mesh;
  EXPECT_EQ(dropMeshFragments(mesh, 0.3), 3u);
  ASSERT_EQ(mesh.vertices_W.size(), 10u);
  ASSERT_EQ(mesh.colours.size(), 10u);
  ASSERT_EQ(mesh.triangles.size(), 4u);
  for (const auto& v : mesh.vertices_W) EXPECT_LT(v.x(), 0.6f);
  for (const auto& t : mesh.triangles)
    for (const std::uint32_t i : t) EXPECT_LT(i, 10u);
  EXPECT_EQ(mesh.triangles[3], (std::array<std::uint32_t, 3>{7, 8, 9}));
  // A gap of 0.22 m keeps the body and the first piece only; 0 keeps everything.
  Mesh narrower = copy;
  EXPECT_EQ(dropMeshFragments(narrower, 0.22), 6u);
  EXPECT_EQ(dropMeshFragments(copy, 0.0), 0u);
  EXPECT_EQ(copy.vertices_W.size(), 13u);
}

TEST(ObjectMasks, ForegroundBeyondAPlaneIsDropped) {
  PinholeCamera cam;
  TsdfMap map(params());
  for (const auto& T_WC : ring(kSphere.centre, 1.0, 0.3, 8)) {
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&kSphere}, depth, labels);
    map.integrate(cam, T_WC, depth, cv::Mat(), labels == 1, true);
  }
  // Drop the half with y > 0.1 m.
  EXPECT_GT(map.dropForegroundBeyond(Eigen::Vector3f::UnitY(), 0.1f), 100u);
  const Mesh mesh = map.extractMesh();
  ASSERT_GT(mesh.vertices_W.size(), 500u);
  float y_max = -1.f;
  for (const auto& v : mesh.vertices_W) y_max = std::max(y_max, v.y());
  EXPECT_LT(y_max, 0.1f + 0.02f);  // within a voxel of the plane
  EXPECT_GT(y_max, 0.1f - 0.04f);
}

}  // namespace
