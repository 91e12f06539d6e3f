// SPDX-License-Identifier: MIT
// Helpers shared by the tests: temporary folders, running the citymesh binary, real data.
#pragma once

#include <filesystem>
#include <map>
#include <string>

namespace citymesh::test {

/// A fresh folder under the system temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

struct CommandResult {
  int exit_code = -1;
  std::string out;  ///< stdout
  std::string err;  ///< stderr
};

/// Runs the built citymesh binary with `args` (shell words, already quoted as needed).
CommandResult run_citymesh(const std::string& args);
/// The same with another executable (a copy of citymesh, say).
CommandResult run_program(const std::filesystem::path& program, const std::string& args);
/// A shell command (/bin/sh), its stderr captured.
CommandResult run_shell(const std::string& command);
/// A copy of the citymesh binary in `dir` with one byte appended: the same program, but
/// another build to citymesh (its executable_identity differs).
std::filesystem::path copy_as_another_build(const std::filesystem::path& dir);

/// The project's source folder (for tests/data, configs, docs).
std::filesystem::path source_dir();
/// ../shared/data/real beside the checkout, or "" when it is absent.
std::filesystem::path real_data_dir();

std::string read_text(const std::filesystem::path& path);

/// Every result file under a run's output folder (PLYs, pair lists, glb, tileset JSON), by
/// relative name: what must not change between equivalent runs. Summaries and run.json hold
/// timings and are left out.
std::map<std::string, std::string> result_bytes(const std::filesystem::path& output);
void write_text(const std::filesystem::path& path, const std::string& text);

/// A synthetic profiler drive of kProfilerLines scan lines, a pulse every degree: a profiler at
/// (651000 + 0.1 line, 6860000, 40) turning in the x = const plane, line l, bin b at angle b
/// degrees, 5 m away; every third pulse has a second echo 1 m further, and the pulses of bin 7
/// of line 2 are missing. Lines [first, last) as ASCII PLY with theta, num_echo, nb_of_echo,
/// gps_time and the sensor origin.
constexpr int kProfilerLines = 5, kProfilerBins = 360;
void write_profiler_lines(const std::filesystem::path& path, int first, int last);

}  // namespace citymesh::test
