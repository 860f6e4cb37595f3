#include "semantic_exploration/core/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace semexp {

namespace fs = std::filesystem;

namespace {

std::string errnoText() { return std::strerror(errno); }

// Flushes the temporary file's data to the device, so that the rename never
// makes a file visible whose contents a crash could still lose.
bool syncFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  return ::close(fd) == 0 && ok;
}

// The process's umask without changing it (umask() sets it, which races with other threads creating files).
unsigned processUmask() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("Umask:", 0) == 0) return static_cast<unsigned>(std::stoul(line.substr(6), nullptr, 8));
  return 022;
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  std::error_code ec;
  fs::path target(path);
  if (fs::is_symlink(fs::symlink_status(target, ec))) {
    target = fs::weakly_canonical(target, ec);
    if (ec) throw std::runtime_error("cannot resolve the link " + path + ": " + ec.message());
  }
  const fs::file_status st = fs::status(target, ec);
  if (fs::exists(st) && !fs::is_regular_file(st))
    throw std::runtime_error("cannot write " + path + ": " +
                             (target.string() == path ? "it" : target.string()) + " is not a regular file");
  // mkstemp: a fresh name in the target's directory (rename stays within one file system).
  std::string tmpl = (target.parent_path() / ("." + target.filename().string() + ".tmp-XXXXXX")).string();
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) throw std::runtime_error("cannot write " + path + ": cannot create a temporary file: " + errnoText());
  ::close(fd);
  const std::string tmp(name.data());
  try {
    {
      std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
      if (!f) throw std::runtime_error("cannot open " + tmp);
      write(f);
      f.flush();
      if (!f) throw std::runtime_error("error writing (device full?)");
      f.close();
      if (f.fail()) throw std::runtime_error("error closing the file (device full?)");
    }
    if (!syncFile(tmp)) throw std::runtime_error("error syncing the file: " + errnoText());
    // mkstemp makes the file 0600; a saved map is as readable as any file the user creates.
    fs::permissions(tmp, static_cast<fs::perms>(0666 & ~processUmask()), fs::perm_options::replace, ec);
    if (::rename(tmp.c_str(), target.c_str()) != 0) throw std::runtime_error("cannot rename it: " + errnoText());
  } catch (const std::exception& e) {
    fs::remove(tmp, ec);
    throw std::runtime_error("cannot write " + path + ": " + e.what() + "; the previous file is unchanged");
  }
}

}  // namespace semexp
