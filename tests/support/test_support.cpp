// SPDX-License-Identifier: MIT
#include "test_support.h"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace citymesh::test {

TempDir::TempDir() {
  std::random_device rd;
  const auto base = std::filesystem::temp_directory_path();
  for (int attempt = 0; attempt < 100; ++attempt) {
    path_ = base / ("citymesh_test_" + std::to_string(::getpid()) + "_" + std::to_string(rd()));
    if (std::filesystem::create_directory(path_)) return;
  }
  throw std::runtime_error("cannot create a temporary folder");
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

CommandResult run_citymesh(const std::string& args) { return run_program(CITYMESH_BINARY, args); }

CommandResult run_program(const std::filesystem::path& program, const std::string& args) {
  return run_shell(program.string() + " " + args);
}

CommandResult run_shell(const std::string& command) {
  TempDir dir;
  const auto err_file = dir / "stderr.txt";
  const std::string redirected = "{ " + command + "; } 2>" + err_file.string();
  CommandResult result;
  FILE* pipe = ::popen(redirected.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("popen failed");
  std::array<char, 4096> buffer{};
  std::size_t n = 0;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.out.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.err = read_text(err_file);
  return result;
}

std::filesystem::path copy_as_another_build(const std::filesystem::path& dir) {
  const std::filesystem::path other = dir / "other-citymesh";
  std::filesystem::copy_file(CITYMESH_BINARY, other, std::filesystem::copy_options::overwrite_existing);
  write_text(other, read_text(other) + "x");
  std::filesystem::permissions(other, std::filesystem::perms::owner_all);
  return other;
}

std::filesystem::path source_dir() { return CITYMESH_SOURCE_DIR; }

std::filesystem::path real_data_dir() {
  const auto dir = source_dir().parent_path() / "shared" / "data" / "real";
  return std::filesystem::is_directory(dir) ? dir : std::filesystem::path();
}

std::map<std::string, std::string> result_bytes(const std::filesystem::path& output) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(output)) {
    const auto ext = e.path().extension();
    const bool tileset = ext == ".json" && e.path().parent_path().filename() == "tiles";
    if (ext == ".ply" || ext == ".bin" || ext == ".glb" || tileset) {
      files[std::filesystem::relative(e.path(), output).string()] = read_text(e.path());
    }
  }
  return files;
}

void write_profiler_lines(const std::filesystem::path& path, int first, int last) {
  std::string body;
  int rows = 0;
  for (int line = first; line < last; ++line) {
    for (int bin = 0; bin < kProfilerBins; ++bin) {
      if (line == 2 && bin == 7) continue;
      const double angle = bin * M_PI / 180.0, sx = 651000 + 0.1 * line;
      const int echoes = bin % 3 == 0 ? 2 : 1;
      for (int echo = 1; echo <= echoes; ++echo) {
        const double range = 5.0 + (echo - 1);
        const double reported = angle;  // in [0, 2 pi): the angle wraps where a line starts
        body += fmt::format("{:.4f} {:.4f} {:.4f} {:.4f} 6860000 40 {} {} {} {:.6f}\n", sx,
                            6860000 + range * std::cos(angle), 40 + range * std::sin(angle), sx, reported + 1e-9, echo,
                            echoes, 100.0 + line + bin * 1e-4);
        ++rows;
      }
    }
  }
  write_text(path, fmt::format("ply\nformat ascii 1.0\nelement vertex {}\nproperty double x\nproperty double y\n"
                               "property double z\nproperty double x_origin\nproperty double y_origin\n"
                               "property double z_origin\nproperty double theta\nproperty int num_echo\n"
                               "property int nb_of_echo\nproperty double gps_time\nend_header\n{}",
                               rows, body));
}

}  // namespace citymesh::test
