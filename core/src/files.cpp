#include "shapematch/files.hpp"

#include "shapematch/errors.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace shapematch {

void write_file_atomic(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  auto discard = [&] {
    std::error_code ignored;
    fs::remove(tmp, ignored);
  };
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw IoError(path + ": cannot write (" + std::strerror(errno) + ")");
    try {
      write(out);
    } catch (...) {
      out.close();
      discard();
      throw;
    }
    out.flush();
    if (!out) {
      discard();
      throw IoError(path + ": write failed");
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    discard();
    throw IoError(path + ": cannot rename into place (" + ec.message() + ")");
  }
}

void write_file_atomic(const std::string& path, const std::string& text) {
  write_file_atomic(path, [&](std::ostream& out) { out << text; });
}

void check_writable_file(const std::string& path) {
  std::error_code ec;
  if (path.empty()) throw IoError("an output file's path is empty");
  if (fs::is_directory(path, ec)) throw IoError(path + ": is a directory, not a file");
  fs::path folder = fs::absolute(path, ec).parent_path();
  if (!fs::is_directory(folder, ec)) throw IoError(path + ": cannot write: its folder " + folder.string() + " does not exist");
  if (::access(folder.c_str(), W_OK) != 0)
    throw IoError(path + ": cannot write in " + folder.string() + " (" + std::strerror(errno) + ")");
}

std::ifstream open_for_reading(const std::string& path, std::ios::openmode mode) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw IoError(path + ": is a directory, not a file");
  std::ifstream in(path, mode | std::ios::in);
  if (!in) throw IoError(path + ": cannot open for reading (" + std::strerror(errno) + ")");
  return in;
}

}  // namespace shapematch
