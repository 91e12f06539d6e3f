// SPDX-License-Identifier: MIT
#include "leftovers.h"

#include <string>
#include <system_error>
#include <vector>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/log.h"
#include "citymesh/tiler/tiler.h"
#include "pair_spill.h"
#include "seam_parts.h"

namespace citymesh::app {

std::string_view process_tag_in_name(std::string_view name, std::string_view parent) {
  if (const std::size_t at = name.rfind(kTemporaryInfix); at != std::string_view::npos && at > 0) {
    return name.substr(at + kTemporaryInfix.size());
  }
  for (const std::string_view prefix : {kPairSpillPrefix, kSeamPartsPrefix}) {
    if (name.starts_with(prefix)) return name.substr(prefix.size());
  }
  if (parent == kStagingFolder && name.size() > 1 && name[0] == 'a') {
    const std::size_t dot = name.find('.');
    const std::string_view index = name.substr(1, dot == std::string_view::npos ? 0 : dot - 1);
    if (!index.empty() && index.find_first_not_of("0123456789") == std::string_view::npos) return name.substr(dot + 1);
  }
  return {};
}

std::size_t remove_leftovers_of_ended_runs(const std::filesystem::path& dir) {
  std::error_code ec;
  std::vector<std::filesystem::path> ended;
  for (auto it = std::filesystem::recursive_directory_iterator(dir, std::filesystem::directory_options::skip_permission_denied, ec); !ec && it != std::filesystem::end(it);
       it.increment(ec)) {
    const std::filesystem::path& path = it->path();
    const std::string name = path.filename().native(), parent = path.parent_path().filename().native();
    const std::string_view tag = process_tag_in_name(name, parent);
    if (tag.empty() || !tag_of_ended_local_process(tag)) continue;
    ended.push_back(path);
    it.disable_recursion_pending();  // removed whole
  }
  std::size_t removed = 0;
  for (const std::filesystem::path& path : ended) {
    std::filesystem::remove_all(path, ec);
    if (ec) {
      log::warn("{}: left by an ended run, but cannot be removed: {}", path.string(), ec.message());
    } else {
      log::info("removed {}, left by an ended run", path.string());
      ++removed;
    }
  }
  return removed;
}

void remove_leftovers_of_ended_runs(const Config& config) {
  remove_leftovers_of_ended_runs(config.project.work);
  if (config.project.output != config.project.work) remove_leftovers_of_ended_runs(config.project.output);
}

}  // namespace citymesh::app
