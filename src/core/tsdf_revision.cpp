// TsdfRevision: one counter for all maps, so that no two maps (or states of one) share a value.
#include "semantic_exploration/core/tsdf_revision.hpp"

#include <atomic>

namespace semexp {

namespace {
std::atomic<std::uint64_t> g_next_revision{1};
std::uint64_t nextRevision() { return g_next_revision.fetch_add(1, std::memory_order_relaxed); }
}  // namespace

TsdfRevision::TsdfRevision() : value_(nextRevision()) {}
TsdfRevision::TsdfRevision(TsdfRevision&& other) noexcept : value_(other.value_) { other.value_ = nextRevision(); }
TsdfRevision& TsdfRevision::operator=(TsdfRevision&& other) noexcept {
  value_ = other.value_;
  other.value_ = nextRevision();
  return *this;
}
void TsdfRevision::bump() { value_ = nextRevision(); }

}  // namespace semexp
