// SPDX-License-Identifier: MIT
#include "output_record.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <string>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/read_file.h"

namespace citymesh::app {

namespace {

/// What the final pass writes under the output folder; anything else there (eval.json, a
/// user's notes) is not the run's and is left out of the record.
constexpr const char* kOutputFolders[] = {"detect", "mosaic", "tiles", "ply"};
constexpr const char* kRunReport = "run.json";

/// A file's size and modification time, as the record keeps them.
nlohmann::json file_state(const std::filesystem::path& path, std::error_code& ec) {
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return {};
  const auto time = std::filesystem::last_write_time(path, ec);
  if (ec) return {};
  return nlohmann::json::array({size, static_cast<std::int64_t>(time.time_since_epoch().count())});
}

/// The run's files under `output`, by path relative to it, with their states.
nlohmann::json output_files(const std::filesystem::path& output) {
  nlohmann::json files = nlohmann::json::object();
  std::error_code ec;
  const auto add = [&](const std::filesystem::path& path) {
    const nlohmann::json state = file_state(path, ec);
    if (!ec) files[path.lexically_relative(output).generic_string()] = state;
  };
  if (std::filesystem::is_regular_file(output / kRunReport, ec)) add(output / kRunReport);
  for (const char* folder : kOutputFolders) {
    if (!std::filesystem::is_directory(output / folder, ec)) continue;
    for (const auto& e : std::filesystem::recursive_directory_iterator(output / folder, ec)) {
      if (e.is_regular_file(ec)) add(e.path());
    }
  }
  return files;
}

}  // namespace

std::filesystem::path output_record_path(const std::filesystem::path& work) { return work / "outputs.json"; }

std::uint64_t final_pass_digest(const Config& config, std::span<const std::uint64_t> result_digests,
                                const PictureOptions& pictures) {
  BulkChecksum sum;
  const auto add_text = [&](const std::string& text) { sum.add_array(std::span<const char>(text)); };
  sum.add_value(executable_identity());
  add_text(config.file.string());
  add_text(effective_config_toml(config));
  sum.add_value(pictures.pixel_size);
  sum.add_value(std::uint8_t{pictures.pictures});
  sum.add_array(result_digests);
  return sum.value();
}

void forget_outputs(const std::filesystem::path& work) {
  std::error_code ec;
  std::filesystem::remove(output_record_path(work), ec);
  if (ec) {
    throw OutputError(fmt::format("{}: cannot remove the record of the last run's outputs: {}",
                                  output_record_path(work).string(), ec.message()));
  }
}

void record_outputs(const Config& config, std::uint64_t digest) {
  const nlohmann::json record{{"digest", fmt::format("{:016x}", digest)},
                              {"files", output_files(config.project.output)}};
  try {
    write_file_atomically(output_record_path(config.project.work), record.dump(1) + "\n");
  } catch (const std::exception& e) {
    log::warn("{} (the next run writes its outputs again)", e.what());
  }
}

bool outputs_up_to_date(const Config& config, std::uint64_t digest) {
  const std::optional<std::string> text = read_file_bytes(output_record_path(config.project.work));
  if (!text) return false;
  const nlohmann::json record = nlohmann::json::parse(*text, nullptr, false);
  if (!record.is_object() || record.value("digest", std::string()) != fmt::format("{:016x}", digest)) return false;
  const auto files = record.find("files");
  if (files == record.end() || !files->is_object() || files->empty()) return false;
  for (const auto& [name, state] : files->items()) {
    std::error_code ec;
    if (file_state(config.project.output / name, ec) != state || ec) return false;
  }
  return true;
}

}  // namespace citymesh::app
