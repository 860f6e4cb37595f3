#pragma once
/// @file config_error.hpp
/// The one exception type for invalid configuration: it names the parameter.

#include <stdexcept>
#include <string>

namespace semexp {

/// Thrown by every Config::validate(); `parameter()` is the parameter's name
/// exactly as it appears in the YAML files (e.g. "background_map/resolution_m").
class ConfigError : public std::invalid_argument {
 public:
  ConfigError(const std::string& parameter, const std::string& why)
      : std::invalid_argument("invalid parameter '" + parameter + "': " + why),
        parameter_(parameter) {}
  const std::string& parameter() const { return parameter_; }

 private:
  std::string parameter_;
};

/// Throws ConfigError(name, why) unless `ok`.
inline void require(bool ok, const std::string& name, const std::string& why) {
  if (!ok) throw ConfigError(name, why);
}

}  // namespace semexp
