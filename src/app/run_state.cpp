// SPDX-License-Identifier: MIT
// Which config a work folder was made with, so that a re-run resumes only compatible work.
#include "run_state.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <vector>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "tiled_run.h"

namespace citymesh::app {

namespace {

bool affects_results(const std::string& section) {
  return section == "input" || section == "change" || section == "mosaic" || section == "tiling" ||
         section.starts_with("acquisition[");
}

/// "acquisition[k] (its path)" for any key of acquisition k.
std::string acquisition_named(const std::map<std::string, std::string>& keys, const std::string& key) {
  const std::string acquisition = key.substr(0, key.find(']') + 1);
  const auto path = keys.find(acquisition + ".path");
  return path == keys.end() ? acquisition : fmt::format("{} ({})", acquisition, path->second);
}

/// "acquisition[1] (/data/b.ply) was rewritten (17500 -> 17547 bytes)" from the `.file`
/// key's two values ("<size> bytes, modified <ticks>"): the ticks mean nothing to a reader.
std::string describe_rewrite(const std::map<std::string, std::string>& keys, const std::string& file_key,
                             const std::string& before, const std::string& after) {
  const std::string where = acquisition_named(keys, file_key);
  const auto size_of = [](const std::string& value) { return std::strtoull(value.c_str(), nullptr, 10); };
  const std::string how = size_of(before) == size_of(after)
                              ? fmt::format("same size, {} bytes, new modification time", size_of(after))
                              : fmt::format("{} -> {} bytes", size_of(before), size_of(after));
  return fmt::format("{} was rewritten since the last run ({})", where, how);
}

/// The `.file` key of a withdrawn acquisition, whose file is not looked at.
constexpr std::string_view kWithdrawnFile = "withdrawn";

/// k of an "acquisition[k]..." key; nothing for other keys.
std::optional<std::size_t> acquisition_of_key(std::string_view key) {
  constexpr std::string_view prefix = "acquisition[";
  if (!key.starts_with(prefix)) return std::nullopt;
  std::size_t k = 0;
  const char* end = key.data() + key.size();
  const auto [at, ec] = std::from_chars(key.data() + prefix.size(), end, k);
  if (ec != std::errc() || at == end || *at != ']') return std::nullopt;
  return k;
}

/// How many acquisitions `keys` describe.
std::size_t acquisition_count(const std::map<std::string, std::string>& keys) {
  std::size_t count = 0;
  for (const auto& entry : keys) {
    if (const std::optional<std::size_t> a = acquisition_of_key(entry.first)) count = std::max(count, *a + 1);
  }
  return count;
}

/// Each acquisition of `keys` as "path|time|name", in their order.
std::vector<std::string> passes_of(const std::map<std::string, std::string>& keys) {
  std::vector<std::string> out(acquisition_count(keys));
  for (std::size_t k = 0; k < out.size(); ++k) {
    const std::string a = fmt::format("acquisition[{}]", k);
    const auto value = [&](const char* key) {
      const auto it = keys.find(a + key);
      return it == keys.end() ? std::string() : it->second;
    };
    out[k] = value(".path") + "|" + value(".time") + "|" + value(".name");
  }
  return out;
}

/// Whether one of `before` and `now` holds every pass the other does, and more besides, not
/// all of them after the others by time: a pass delivered late, older than passes already
/// processed, or a pass removed before the last. Acquisitions are numbered by time, so the
/// passes after it are renumbered: input too, as an appended or withdrawn pass is (the tiles
/// it reaches are redone; the others' results, the tilings and the seam parts are found by
/// identity and renumbered, to the bytes of a fresh run). False for passes appended or
/// removed after all the others: the keys tell those apart one by one.
bool passes_added_or_removed(const std::map<std::string, std::string>& before,
                             const std::map<std::string, std::string>& now) {
  std::vector<std::string> fewer = passes_of(before), more = passes_of(now);
  if (fewer.size() > more.size()) std::swap(fewer, more);
  if (fewer.size() == more.size() || std::equal(fewer.begin(), fewer.end(), more.begin())) return false;
  std::sort(fewer.begin(), fewer.end());
  std::sort(more.begin(), more.end());
  return std::includes(more.begin(), more.end(), fewer.begin(), fewer.end());
}

std::string trim(std::string s) {
  const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

/// How an acquisition's file is named in the keys: the file, not the spelling, so that the
/// same config given as out/config.toml or as /data/out/config.toml (another working
/// directory) resumes the same work; and relative to the config's folder when the file lies
/// under it, so that a project folder moved or renamed whole (config, acquisitions, work)
/// resumes too. A file elsewhere is named by its absolute path.
std::string path_key(const std::filesystem::path& file, const std::filesystem::path& config_dir) {
  const std::filesystem::path absolute = std::filesystem::absolute(file).lexically_normal();
  if (config_dir.empty()) return absolute.generic_string();
  const std::filesystem::path relative =
      absolute.lexically_relative(std::filesystem::absolute(config_dir).lexically_normal());
  const bool under = !relative.empty() && *relative.begin() != "..";
  return under ? relative.generic_string() : absolute.generic_string();
}

/// Whether `before`, an absolute path, names the file `now` names relative to the config's
/// folder (a work folder recorded before session 60).
bool named_before_relative_paths(const std::string& before, const std::string& now) {
  const std::filesystem::path old_path(before), new_path(now);
  return old_path.is_absolute() && new_path.is_relative() && before.ends_with("/" + now);
}

}  // namespace

std::map<std::string, std::string> result_keys(const Config& config) {
  std::map<std::string, std::string> keys;
  // Numbered as every step numbers the acquisitions (by time), so that listing them in
  // another order resumes the work: the results do not depend on it.
  std::istringstream in(effective_config_toml(config, TableOrder::processing));
  std::string line, section;
  int acquisition = -1;
  while (std::getline(in, line)) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    if (line == "[[acquisition]]") {
      section = fmt::format("acquisition[{}]", ++acquisition);
    } else if (line[0] == '[') {
      section = line.substr(1, line.size() - 2);
    } else if (const auto eq = line.find('='); eq != std::string::npos && affects_results(section)) {
      keys[section + "." + trim(line.substr(0, eq))] = trim(line.substr(eq + 1));
    }
  }
  for (std::size_t k = 0; k < config.acquisitions.size(); ++k) {
    const auto& path = config.acquisitions[k].path;
    keys[fmt::format("acquisition[{}].path", k)] = path_key(path, config.base_dir);
    if (config.acquisitions[k].withdrawn) {
      keys[fmt::format("acquisition[{}].file", k)] = std::string(kWithdrawnFile);  // not read: may be gone
      continue;
    }
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    const auto time = std::filesystem::last_write_time(path, ec).time_since_epoch().count();
    keys[fmt::format("acquisition[{}].file", k)] = fmt::format("{} bytes, modified {}", size, time);
  }
  return keys;
}

std::string build_name() { return fmt::format("{:016x}", executable_identity()); }

RunFingerprints run_fingerprints(const std::map<std::string, std::string>& keys, std::size_t acquisitions) {
  // The formats' versions are part of each: work made by an older build is redone, not misread.
  // The tile results also depend on the build itself (its code decides what they hold): another
  // build's are made again, never mixed with this one's. The tile store's layout is all its
  // version says, so it is kept across builds.
  const std::string versions = fmt::format("tile store {}, tile results {}\n", kTileStoreVersion, kTileResultVersion);
  std::string settings = versions + "build " + build_name() + "\n", tiling = versions;
  std::vector<std::string> own(acquisitions), identity(acquisitions);
  for (const auto& [k, v] : keys) {
    const std::string line = k + "=" + v + "\n";
    if (const std::optional<std::size_t> a = acquisition_of_key(k)) {
      if (*a >= acquisitions) continue;
      own[*a] += line;
      identity[*a] += line.substr(line.find("].") + 2);  // "acquisition[k].path=..." as "path=..."
      continue;
    }
    settings += line;
    if (k.starts_with("input.") || k.starts_with("tiling.")) tiling += line;
  }
  const auto hash = [](const std::string& text) { return fnv1a(text.data(), text.size()); };
  RunFingerprints f;
  f.settings = hash(settings);
  std::string store = tiling;
  for (const std::string& lines : own) store += lines;
  for (const std::string& lines : identity) {
    f.acquisitions.push_back(hash(tiling + lines));
    f.identities.push_back(hash(lines));
  }
  f.store = hash(store);
  return f;
}

void check_run_config_unrecorded(const std::filesystem::path& work, const std::map<std::string, std::string>& keys,
                                 bool force) {
  const std::filesystem::path file = work / kRunConfigFile;
  std::ifstream in(file);
  const std::string build = build_name();
  if (in) {
    std::map<std::string, std::string> before;
    try {
      const nlohmann::json recorded = nlohmann::json::parse(in);
      before = recorded.at("keys").get<std::map<std::string, std::string>>();
      if (recorded.value("build", std::string()) != build) {
        log::info(
            "{}: the work there was made by another build of citymesh: its tile results, stitched parts "
            "and encoded tiles are made again (its tiling is kept)",
            work.string());
      }
    } catch (const nlohmann::json::exception& e) {
      if (!force)
        throw InputError(fmt::format(
            "{}: malformed ({}); run with --force to record this config anew (the finished work whose inputs "
            "match is still reused)",
            file.string(), e.what()));
    }
    std::vector<std::string> changed;
    const std::size_t recorded = acquisition_count(before);
    const bool renumbered = passes_added_or_removed(before, keys);
    if (const std::size_t now = acquisition_count(keys); renumbered && now > recorded) {
      log::info(
          "{} pass(es) added since the last run, older than passes already processed: the tiles they reach "
          "are redone; the passes after them by time are renumbered, and so are their tiling and the other "
          "tiles' results",
          now - recorded);
    } else if (renumbered) {
      log::info(
          "{} pass(es) removed since the last run, older than the newest: the tiles they reached are redone; "
          "the passes after them by time are renumbered, and so are their tiling and the other tiles' results",
          recorded - now);
    }
    for (const auto& [k, v] : keys) {
      if (renumbered && acquisition_of_key(k)) continue;
      const auto it = before.find(k);
      // An acquisition appended (a new pass over part of the city) is input, not a config
      // change: the tiles it reaches are processed, the others reused.
      if (const std::optional<std::size_t> a = acquisition_of_key(k); a && *a >= recorded) {
        if (k.ends_with(".path"))
          log::info("{} ({}) was added since the last run: the tiles it reaches are redone", k.substr(0, k.size() - 5),
                    v);
        continue;
      }
      // Before session 60 every file was named by its absolute path: the same file, now named
      // relative to the config's folder, is no changed key (its tiles are redone once, their
      // digests having changed).
      if (k.ends_with(".path") && it != before.end() && named_before_relative_paths(it->second, v)) continue;
      const std::string what = it == before.end() ? fmt::format("{} (new: {})", k, v)
                               : it->second != v  ? fmt::format("{} ({} -> {})", k, it->second, v)
                                                  : std::string();
      if (what.empty()) continue;
      // A pass withdrawn in place, or put back, is input too: no pass is renumbered.
      if (k.ends_with(".withdrawn")) {
        log::info("{} was withdrawn since the last run: the tiles it reached are redone", acquisition_named(keys, k));
        continue;
      }
      if (k.ends_with(".file") && it != before.end() && (it->second == kWithdrawnFile || v == kWithdrawnFile)) continue;
      // A rewritten input file is not a config change: its tiles are simply redone.
      if (k.ends_with(".file")) {
        log::warn("{}: its work is redone", it == before.end()
                                                ? fmt::format("{} changed since the last run ({})", k, what)
                                                : describe_rewrite(keys, k, it->second, v));
      } else {
        changed.push_back(what);
      }
    }
    const std::size_t listed = acquisition_count(keys);
    for (const auto& [k, v] : before) {
      if (keys.contains(k)) continue;
      const std::optional<std::size_t> a = acquisition_of_key(k);
      if (renumbered && a) continue;
      if (a && *a < listed && k.ends_with(".withdrawn")) {
        log::info("{} is no longer withdrawn: the tiles it reaches are redone", acquisition_named(keys, k));
        continue;
      }
      // The last acquisitions withdrawn (a pass found faulty, an update undone) are input too:
      // no other pass is renumbered, so only the tiles they reached are redone.
      if (a && *a >= listed) {
        if (k.ends_with(".path"))
          log::info("{} was withdrawn since the last run: the tiles it reached are redone",
                    acquisition_named(before, k));
        continue;
      }
      changed.push_back(fmt::format("{} (gone)", k));
    }
    if (!changed.empty() && !force) {
      throw ConfigError(
          fmt::format("{}: the work there was done with another config; changed: {}. Run with --force to "
                      "discard it, or choose another [project] work folder",
                      work.string(), fmt::join(changed, "; ")));
    }
  }
}

void check_run_config(const std::filesystem::path& work, const std::map<std::string, std::string>& keys, bool force) {
  check_run_config_unrecorded(work, keys, force);
  std::filesystem::create_directories(work);
  write_file_atomically(work / kRunConfigFile, nlohmann::json{{"keys", keys}, {"build", build_name()}}.dump(1) + "\n");
}

}  // namespace citymesh::app
