// Min/max pyramid of one depth frame.
#include "semantic_exploration/core/occupancy/depth_pyramid.hpp"

#include <algorithm>
#include <limits>

namespace semexp {
namespace occupancy {

std::size_t DepthPyramid::build(const float* depth_m, int W, int H, float dmin, float dmax, float front,
                                float quad) {
  depth_.resize(static_cast<std::size_t>(W) * H);
  free_.resize(depth_.size());
  std::size_t invalid = 0;
  for (std::size_t i = 0; i < depth_.size(); ++i) {
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
    for (int v = 0; v < nd.y(); ++v)
      for (int u = 0; u < nd.x(); ++u) {
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
