#pragma once
/// @file tsdf_revision.hpp
/// TsdfMapT::revision(): a value that changes with every change of a map and
/// differs between any two maps of the process, so that a cache keyed by it
/// (ObjectSummaryCache) is never taken for a state it was not computed from.

#include <cstdint>

namespace semexp {

class TsdfRevision {
 public:
  TsdfRevision();  ///< the next value of a process-wide counter
  /// Moving hands the value over and gives the source a new one (it holds another state now).
  TsdfRevision(TsdfRevision&& other) noexcept;
  TsdfRevision& operator=(TsdfRevision&& other) noexcept;
  TsdfRevision(const TsdfRevision&) = delete;
  TsdfRevision& operator=(const TsdfRevision&) = delete;
  void bump();  ///< the map changed: a new value
  std::uint64_t value() const { return value_; }

 private:
  std::uint64_t value_;
};

}  // namespace semexp
