#pragma once
// The exception hierarchy of shapematch. Every error that reaches the command line is one of
// these; what() is a single line that names the file (if any) and the problem.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace shapematch {

class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// Input that violates a documented precondition (bad mesh, bad option value, bad file content).
class InvalidInputError : public Error {
public:
  using Error::Error;
};

// A file could not be opened, read or written.
class IoError : public Error {
public:
  using Error::Error;
};

// A solver failed as a program (not as an LP: infeasibility is a status, not an exception).
class SolverError : public Error {
public:
  using Error::Error;
};

// A whole problem turned out to have no solution (e.g. a coarse-to-fine search space too narrow
// to hold any matching); callers may widen the problem and retry.
class InfeasibleError : public SolverError {
public:
  using SolverError::SolverError;
  InfeasibleError(const std::string& what, std::vector<int64_t> rows, bool certified = true)
      : SolverError(what), rows_(std::move(rows)), certified_(certified) {}
  // Rows of the problem's constraint system where the proof lies (the support of a Farkas
  // certificate, or the row propagation emptied), so a caller can widen there; may be empty.
  const std::vector<int64_t>& rows() const { return rows_; }
  // False where the LP only behaved like an infeasible one (LpStatus::Diverging).
  bool certified() const { return certified_; }

private:
  std::vector<int64_t> rows_;
  bool certified_ = true;
};

// No usable Vulkan device, out of device memory, a failed Vulkan call.
class DeviceError : public Error {
public:
  using Error::Error;
};

// Thrown where a run leaves off after request_stop (system.hpp), once what could be saved is.
// Not an Error: nothing retries or works around it (the command line exits 128 + the signal).
class Stopped : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

}  // namespace shapematch
