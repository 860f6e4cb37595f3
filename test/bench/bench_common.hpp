#pragma once
// Shared helpers of the benchmark programs: timing, medians and the JSON-line
// output that `make bench` collects under results/bench/.
//
// Every benchmark program accepts `--out FILE` (append JSON lines there;
// default: stdout only) and prints a human-readable table as well.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace semexp_bench {

using Clock = std::chrono::steady_clock;

inline double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Collects figures and writes them as JSON lines:
/// {"name":..., "value":..., "unit":..., "peer":..., "peer_value":...}
class Reporter {
 public:
  Reporter(int argc, char** argv) {
    for (int i = 1; i + 1 < argc; ++i)
      if (std::strcmp(argv[i], "--out") == 0) out_path_ = argv[i + 1];
  }

  /// A figure with a peer measured in the same run (peer may be empty).
  void add(const std::string& name, double value, const std::string& unit, const std::string& peer = "",
           double peer_value = 0.0) {
    char buf[512];
    if (peer.empty())
      std::snprintf(buf, sizeof(buf), "{\"name\": \"%s\", \"value\": %.6g, \"unit\": \"%s\", \"peer\": null, \"peer_value\": null}",
                    name.c_str(), value, unit.c_str());
    else
      std::snprintf(buf, sizeof(buf), "{\"name\": \"%s\", \"value\": %.6g, \"unit\": \"%s\", \"peer\": \"%s\", \"peer_value\": %.6g}",
                    name.c_str(), value, unit.c_str(), peer.c_str(), peer_value);
    std::printf("%s\n", buf);
    lines_.emplace_back(buf);
  }

  ~Reporter() {
    if (out_path_.empty()) return;
    std::ofstream f(out_path_, std::ios::app);
    for (const auto& l : lines_) f << l << "\n";
  }

 private:
  std::string out_path_;
  std::vector<std::string> lines_;
};

}  // namespace semexp_bench
