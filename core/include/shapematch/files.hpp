#pragma once
// Output files are written next to their target and renamed over it, so that no reader (and no
// failed run) ever sees a half-written file.
#include <fstream>
#include <functional>
#include <ostream>
#include <string>

namespace shapematch {

// Calls write(stream) on a temporary file, then renames it to `path`. Throws IoError naming the
// path; the temporary is removed on failure.
void write_file_atomic(const std::string& path, const std::function<void(std::ostream&)>& write);
void write_file_atomic(const std::string& path, const std::string& text);

// `path` opened for reading, or an IoError naming it and why not ("is a directory", the
// system's reason): a directory opens as a stream that fails only at its first read, which
// readers would report as a truncated or malformed file.
std::ifstream open_for_reading(const std::string& path, std::ios::openmode mode = std::ios::in);

// Throws IoError naming `path` where a file could not be written there (it is a directory, its
// folder is missing or not writable): checked before the work whose result it is to hold.
void check_writable_file(const std::string& path);

}  // namespace shapematch
