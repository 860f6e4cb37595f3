// Min/max pyramid of one depth frame.
#include "semantic_exploration/core/occupancy/depth_pyramid.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

#include "lanes.hpp"

namespace semexp {
namespace occupancy {

std::size_t DepthPyramid::build(const float* depth_m, int W, int H, float dmin, float dmax, float front,
                                float quad) {
  depth_.resize(static_cast<std::size_t>(W) * H);
  free_.resize(depth_.size());
  std::size_t invalid = 0;
  std::size_t i = 0;
  {
    // Four pixels at a time, the same operations as the loop below.
    using lanes::Vf;
    using lanes::Vi;
    Vi invalid4 = {};
    const Vf zero = {}, frontv = zero + front;
    for (; i + lanes::kLanes <= depth_.size(); i += lanes::kLanes) {
      Vf d;
      std::memcpy(&d, depth_m + i, sizeof(d));
      const Vi ok = (d > 0.f) & (d >= dmin) & (d <= dmax);
      const Vf q = quad * d * d;
      const Vf f = d - lanes::select(front < q, q, frontv);  // d - std::max(front, q)
      const Vf fr = lanes::select(0.f < f, f, zero);         // std::max(0.f, f)
      const Vf dv = lanes::floats(lanes::bits(d) & ok), fv = lanes::floats(lanes::bits(fr) & ok);
      std::memcpy(depth_.data() + i, &dv, sizeof(dv));
      std::memcpy(free_.data() + i, &fv, sizeof(fv));
      invalid4 += ok + 1;  // ok is -1 or 0
    }
    for (int k = 0; k < lanes::kLanes; ++k) invalid += static_cast<std::size_t>(invalid4[k]);
  }
  for (; i < depth_.size(); ++i) {
    const float d = depth_m[i];
    const bool ok = d > 0.f && d >= dmin && d <= dmax;  // false for NaN; inf > dmax
    depth_[i] = ok ? d : 0.f;
    free_[i] = ok ? std::max(0.f, d - std::max(front, quad * d * d)) : 0.f;
    invalid += !ok;
  }
  dims_.assign(1, Eigen::Vector2i(W, H));
  min_.resize(1);
  max_.resize(1);
  while (dims_.back().x() > 1 || dims_.back().y() > 1) {
    const Eigen::Vector2i pd = dims_.back();
    const Eigen::Vector2i nd((pd.x() + 1) / 2, (pd.y() + 1) / 2);
    const std::size_t j = dims_.size();
    dims_.push_back(nd);
    min_.resize(j + 1);
    max_.resize(j + 1);
    min_[j].assign(static_cast<std::size_t>(nd.x()) * nd.y(), 0.f);
    max_[j].assign(static_cast<std::size_t>(nd.x()) * nd.y(), 0.f);
    const float* pmn = j == 1 ? free_.data() : min_[j - 1].data();
    const float* pmx = j == 1 ? depth_.data() : max_[j - 1].data();
    // Nodes whose four children exist (all but the last column / row of an odd level).
    const int full_u = pd.x() / 2, full_v = pd.y() / 2;
    for (int v = 0; v < full_v; ++v) {
      const float* mn0 = pmn + 2 * v * pd.x();
      const float* mn1 = mn0 + pd.x();
      const float* mx0 = pmx + 2 * v * pd.x();
      const float* mx1 = mx0 + pd.x();
      float* omn = min_[j].data() + v * nd.x();
      float* omx = max_[j].data() + v * nd.x();
      for (int u = 0; u < full_u; ++u) {
        omn[u] = std::min(std::min(mn0[2 * u], mn0[2 * u + 1]), std::min(mn1[2 * u], mn1[2 * u + 1]));
        omx[u] = std::max(std::max(mx0[2 * u], mx0[2 * u + 1]), std::max(mx1[2 * u], mx1[2 * u + 1]));
      }
    }
    for (int v = 0; v < nd.y(); ++v)
      for (int u = v < full_v ? full_u : 0; u < nd.x(); ++u) {
        float mn = std::numeric_limits<float>::infinity(), mx = 0.f;
        for (int dv = 0; dv < 2; ++dv)
          for (int du = 0; du < 2; ++du) {
            const int uu = 2 * u + du, vv = 2 * v + dv;
            if (uu >= pd.x() || vv >= pd.y()) continue;
            mn = std::min(mn, pmn[vv * pd.x() + uu]);
            mx = std::max(mx, pmx[vv * pd.x() + uu]);
          }
        min_[j][v * nd.x() + u] = mn;
        max_[j][v * nd.x() + u] = mx;
      }
  }
  return invalid;
}

void DepthPyramid::query(int u0, int u1, int v0, int v1, float& mn, float& mx) const {
  std::size_t j = 0;
  while (((u1 >> j) - (u0 >> j)) > 3 || ((v1 >> j) - (v0 >> j)) > 3) ++j;
  const int w = dims_[j].x();
  const float* pmn = j == 0 ? free_.data() : min_[j].data();
  const float* pmx = j == 0 ? depth_.data() : max_[j].data();
  mn = std::numeric_limits<float>::infinity();
  mx = 0.f;
  for (int v = v0 >> j; v <= (v1 >> j); ++v)
    for (int u = u0 >> j; u <= (u1 >> j); ++u) {
      mn = std::min(mn, pmn[v * w + u]);
      mx = std::max(mx, pmx[v * w + u]);
    }
}

std::size_t DepthPyramid::memoryBytes() const {
  std::size_t m = (depth_.capacity() + free_.capacity()) * sizeof(float);
  for (const auto& p : min_) m += p.capacity() * sizeof(float);
  for (const auto& p : max_) m += p.capacity() * sizeof(float);
  return m;
}

}  // namespace occupancy
}  // namespace semexp
