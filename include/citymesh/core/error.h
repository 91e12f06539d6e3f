// SPDX-License-Identifier: MIT
// The exception set of citymesh: one root, one subclass per exit code.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace citymesh {

/// Process exit codes; every failure maps onto exactly one of them.
enum class ExitCode : int {
  ok = 0,
  usage = 1,        ///< bad command line or configuration
  input = 2,        ///< unreadable or malformed input data
  processing = 3,   ///< an algorithm failed (internal error, resource exhausted)
  output = 4,       ///< could not write results
  interrupted = 75, ///< stopped by a signal; re-running resumes (EX_TEMPFAIL)
};

/// Root of every citymesh exception. The message carries its own context,
/// e.g. "info: acq_3.ply: vertex 17: coordinate x is NaN".
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
  [[nodiscard]] virtual ExitCode exit_code() const noexcept { return ExitCode::processing; }
  /// Short class name printed in logs and JSON reports ("input", "config", ...).
  [[nodiscard]] virtual std::string_view kind() const noexcept { return "processing"; }
};

/// Wrong command-line usage.
class UsageError : public Error {
 public:
  using Error::Error;
  [[nodiscard]] ExitCode exit_code() const noexcept override { return ExitCode::usage; }
  [[nodiscard]] std::string_view kind() const noexcept override { return "usage"; }
};

/// Invalid configuration file, key or value.
class ConfigError : public Error {
 public:
  using Error::Error;
  [[nodiscard]] ExitCode exit_code() const noexcept override { return ExitCode::usage; }
  [[nodiscard]] std::string_view kind() const noexcept override { return "config"; }
};

/// Missing, unreadable or malformed input data.
class InputError : public Error {
 public:
  using Error::Error;
  [[nodiscard]] ExitCode exit_code() const noexcept override { return ExitCode::input; }
  [[nodiscard]] std::string_view kind() const noexcept override { return "input"; }
};

/// A processing step failed.
class ProcessingError : public Error {
 public:
  using Error::Error;
};

/// Results could not be written.
class OutputError : public Error {
 public:
  using Error::Error;
  [[nodiscard]] ExitCode exit_code() const noexcept override { return ExitCode::output; }
  [[nodiscard]] std::string_view kind() const noexcept override { return "output"; }
};

/// The run was stopped by SIGINT/SIGTERM.
class InterruptedError : public Error {
 public:
  using Error::Error;
  [[nodiscard]] ExitCode exit_code() const noexcept override { return ExitCode::interrupted; }
  [[nodiscard]] std::string_view kind() const noexcept override { return "interrupted"; }
};

}  // namespace citymesh
