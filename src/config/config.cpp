// SPDX-License-Identifier: MIT
// Config parsing and validation: TOML text -> Config, unknown keys refused with a suggestion.
#include "citymesh/config/config.h"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <span>
#include <sstream>

#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "config_keys.h"

namespace citymesh {

std::string_view seam_pass_name(SeamPass p) {
  switch (p) {
    case SeamPass::whole: return "whole";
    case SeamPass::blocks: return "blocks";
    default: return "auto";
  }
}

using namespace config_detail;

namespace {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

std::string nearest(std::string_view wrong, const std::vector<std::string>& valid) {
  return *std::min_element(valid.begin(), valid.end(), [&](const std::string& x, const std::string& y) {
    return edit_distance(wrong, x) < edit_distance(wrong, y);
  });
}

std::vector<std::string> all_key_names() {
  std::vector<std::string> names;
  for (const KeyDef& k : config_keys()) names.push_back(k.full_name());
  for (std::string_view a : acquisition_keys()) names.push_back("acquisition." + std::string(a));
  return names;
}

class Parser {
 public:
  Parser(const std::filesystem::path& source, const ConfigLoadParams& params)
      : source_(source), params_(params) {
    config_.file = source;
    config_.base_dir = source.has_parent_path() ? source.parent_path() : std::filesystem::path(".");
  }

  Config parse(std::string_view text) {
    toml::table root = parse_toml(text);
    apply_overrides(root);
    for (auto&& [key, node] : root) {
      const std::string name(key.str());
      if (name == "acquisition") {
        read_acquisitions(node);
      } else if (std::find(config_sections().begin(), config_sections().end(), name) != config_sections().end()) {
        read_section(name, node);
      } else {
        std::vector<std::string> valid(config_sections().begin(), config_sections().end());
        valid.emplace_back("acquisition");
        context(node, name).fail(fmt::format("unknown section; did you mean '{}'?", nearest(name, valid)));
      }
    }
    // Like the acquisitions' paths: relative to the config file's folder, not to the caller's.
    config_.project.output = (config_.base_dir / config_.project.output).lexically_normal();
    config_.project.work = (config_.base_dir / config_.project.work).lexically_normal();
    validate();  // its messages name the acquisitions by their place in the file
    std::stable_sort(config_.acquisitions.begin(), config_.acquisitions.end(),
                     [](const AcquisitionEntry& a, const AcquisitionEntry& b) { return a.time < b.time; });
    note_late_tables();
    return std::move(config_);
  }

 private:
  toml::table parse_toml(std::string_view text) const {
    try {
      return toml::parse(text, source_.string());
    } catch (const toml::parse_error& e) {
      throw ConfigError(fmt::format("{}:{}:{}: {}", source_.string(), e.source().begin.line,
                                    e.source().begin.column, e.description()));
    }
  }

  /// Each override is parsed as a one-line TOML document and merged over the file's tables.
  void apply_overrides(toml::table& root) const {
    for (const std::string& o : params_.overrides) {
      const auto eq = o.find('=');
      if (eq == std::string::npos) throw UsageError(fmt::format("--set '{}': expected section.key=value", o));
      const std::string key = o.substr(0, eq), value = o.substr(eq + 1);
      toml::table patch;
      try {
        patch = toml::parse(std::string_view(key + " = " + value), std::string_view("--set"));
      } catch (const toml::parse_error&) {
        patch = toml::parse(std::string_view(key + " = " + toml_string(value)), std::string_view("--set"));  // a bare word is a string
      }
      merge(root, patch);
    }
  }

  static void merge(toml::table& into, const toml::table& patch) {
    for (auto&& [key, node] : patch) {
      toml::table* sub_into = into[key].as_table();
      if (sub_into != nullptr && node.is_table()) {
        merge(*sub_into, *node.as_table());
      } else {
        into.insert_or_assign(key, node);
      }
    }
  }

  KeyContext context(const toml::node& node, std::string_view key) const {
    const auto& where = node.source().begin;
    if (where.line == 0) return {fmt::format("{}: {}", source_.string(), key)};
    return {fmt::format("{}:{}:{}: {}", source_.string(), where.line, where.column, key)};
  }

  void read_section(const std::string& section, const toml::node& node) {
    const toml::table* table = node.as_table();
    if (table == nullptr) context(node, section).fail("expected a [section] table");
    for (auto&& [key, value] : *table) {
      const std::string full = section + "." + std::string(key.str());
      const auto& keys = config_keys();
      auto def = std::find_if(keys.begin(), keys.end(), [&](const KeyDef& k) { return k.full_name() == full; });
      if (def == keys.end()) {
        context(value, full).fail(fmt::format("unknown key; did you mean '{}'?", nearest(full, all_key_names())));
      }
      def->read(config_, value, context(value, full));
      seen_.push_back(full);
    }
  }

  void read_acquisitions(const toml::node& node) {
    const toml::array* list = node.as_array();
    if (list == nullptr) context(node, "acquisition").fail("write each acquisition as an [[acquisition]] table");
    for (std::size_t i = 0; i < list->size(); ++i) {
      const toml::table* t = (*list)[i].as_table();
      const std::string label = fmt::format("acquisition[{}]", i);
      if (t == nullptr) context((*list)[i], label).fail("expected an [[acquisition]] table");
      config_.acquisitions.push_back(read_acquisition(*t, label));
      config_.acquisitions.back().listed = static_cast<std::uint32_t>(i);
    }
  }

  AcquisitionEntry read_acquisition(const toml::table& t, const std::string& label) const {
    AcquisitionEntry a;
    for (auto&& [key, value] : t) {
      const std::string k(key.str());
      const KeyContext ctx = context(value, label + "." + k);
      if (k == "path") {
        if (!value.is_string() || value.value<std::string>()->empty()) ctx.fail("expected a file path string");
        a.path = (config_.base_dir / *value.value<std::string>()).lexically_normal();
      } else if (k == "time") {
        a.time = read_time(value, ctx);
      } else if (k == "name") {
        if (!value.is_string()) ctx.fail("expected a string");
        a.name = *value.value<std::string>();
      } else if (k == "withdrawn") {
        if (!value.is_boolean()) ctx.fail("expected true or false");
        a.withdrawn = *value.value<bool>();
      } else {
        std::vector<std::string> valid(acquisition_keys().begin(), acquisition_keys().end());
        ctx.fail(fmt::format("unknown key; did you mean '{}'?", nearest(k, valid)));
      }
    }
    if (a.path.empty()) context(t, label).fail("missing 'path'");
    if (!t.contains("time")) context(t, label).fail("missing 'time' (ISO 8601 UTC date, e.g. \"2026-01-05T10:00:00Z\")");
    if (a.name.empty()) a.name = a.path.stem().string();
    return a;
  }

  static TimePoint read_time(const toml::node& value, const KeyContext& ctx) {
    if (value.is_string()) return parse_iso8601(*value.value<std::string>(), ctx.where);
    if (const auto* d = value.as_date()) {
      return parse_iso8601(fmt::format("{:04}-{:02}-{:02}", d->get().year, d->get().month, d->get().day), ctx.where);
    }
    if (const auto* dt = value.as_date_time()) {
      if (!dt->get().offset) ctx.fail("a date-time needs a time zone: Z or +hh:mm");
      std::ostringstream text;
      text << dt->get();
      return parse_iso8601(text.str(), ctx.where);
    }
    ctx.fail("expected an ISO 8601 date or date-time");
  }

  [[noreturn]] void fail(std::string_view why) const {
    throw ConfigError(fmt::format("{}: {}", source_.string(), why));
  }

  void require(std::string_view key) const {
    if (std::find(seen_.begin(), seen_.end(), key) == seen_.end()) {
      const auto& keys = config_keys();
      auto def = std::find_if(keys.begin(), keys.end(), [&](const KeyDef& k) { return k.full_name() == key; });
      fail(fmt::format("{} is required (for example {} = {})", key, def->name, def->example));
    }
  }

  void validate() const {
    require("project.crs");
    require("project.vertical_datum");
    try {
      Crs::parse(config_.project.crs, parse_vertical_datum(config_.project.vertical_datum,
                                                           config_.project.geoid_undulation));
    } catch (const ConfigError& e) {
      fail(fmt::format("project: {}", e.what()));
    }
    if (config_.tiling.halo * 2 >= config_.tiling.tile_size) {
      fail(fmt::format("tiling.halo ({} m) must be less than half of tiling.tile_size ({} m)",
                       config_.tiling.halo, config_.tiling.tile_size));
    }
    if (config_.acquisitions.empty()) fail("no [[acquisition]] tables: a run needs at least one acquisition");
    if (std::all_of(config_.acquisitions.begin(), config_.acquisitions.end(),
                    [](const AcquisitionEntry& a) { return a.withdrawn; })) {
      fail("every [[acquisition]] is withdrawn: a run needs at least one acquisition");
    }
    for (std::size_t i = 0; i < config_.acquisitions.size(); ++i) check_acquisition(i);
  }

  /// Says which tables the file lists after newer ones (a pass delivered late), once sorted:
  /// those processed before their place in the file.
  void note_late_tables() const {
    for (std::size_t k = 0; k < config_.acquisitions.size(); ++k) {
      const AcquisitionEntry& a = config_.acquisitions[k];
      if (a.listed <= k) continue;
      log::info(
          "{}: acquisition[{}] ({}) is listed after newer passes: it is processed {} by time, and the "
          "outputs name it {} (source_acq)",
          source_.string(), a.listed, a.name, ordinal(k + 1), a.listed);
    }
  }

  static std::string ordinal(std::size_t n) {
    const char* suffix = n % 100 >= 11 && n % 100 <= 13 ? "th"
                         : n % 10 == 1                  ? "st"
                         : n % 10 == 2                  ? "nd"
                         : n % 10 == 3                  ? "rd"
                                                        : "th";
    return fmt::format("{}{}", n, suffix);
  }

  void check_acquisition(std::size_t i) const {
    const AcquisitionEntry& a = config_.acquisitions[i];
    if (a.withdrawn) return;  // not read: its file may be gone, or listed again as a new pass
    if (params_.check_files && !std::filesystem::is_regular_file(a.path)) {
      fail(fmt::format("acquisition[{}].path: no such file: {}", i, a.path.string()));
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (config_.acquisitions[j].withdrawn) continue;
      if (config_.acquisitions[j].path == a.path) {
        fail(fmt::format("acquisition[{}] and acquisition[{}] name the same file {}", j, i, a.path.string()));
      }
      if (config_.acquisitions[j].time == a.time) {
        log::warn("{}: acquisition[{}] and acquisition[{}] have the same time {}: neither counts as newer",
                  source_.string(), j, i, format_iso8601(a.time));
      }
    }
  }

  const std::filesystem::path& source_;
  const ConfigLoadParams& params_;
  Config config_;
  std::vector<std::string> seen_;
};

/// `c`'s acquisitions in the order `order` names.
std::vector<const AcquisitionEntry*> tables_in(const Config& c, TableOrder order) {
  std::vector<const AcquisitionEntry*> out;
  if (order == TableOrder::listed) {
    for (const std::size_t k : c.listed_order()) out.push_back(&c.acquisitions[k]);
  } else {
    for (const AcquisitionEntry& a : c.acquisitions) out.push_back(&a);
  }
  return out;
}

std::string render(const Config& c, bool defaults, TableOrder order) {
  std::string out;
  if (defaults) {
    out += "# citymesh configuration: every key with its default value and meaning.\n"
           "# Keys marked (required) have no default; they are shown commented out with an example.\n"
           "# Relative paths resolve against the folder of the config file.\n";
  } else {
    out += fmt::format("# effective configuration of {}\n", c.file.string());
  }
  for (std::string_view section : config_sections()) {
    out += fmt::format("\n[{}]\n", section);
    for (const KeyDef& k : config_keys()) {
      if (k.section != section) continue;
      const std::string value = k.show(c);
      out += fmt::format("# {}{}\n", k.required() ? "(required) " : "", k.help);
      if (value.empty()) {
        out += fmt::format("# {} = {}\n", k.name, k.example);
      } else {
        out += fmt::format("{} = {}\n", k.name, value);
      }
    }
  }
  if (defaults) {
    out +=
        "\n# One [[acquisition]] table per pass; its position in the file is its index in the outputs.\n"
        "# Passes are processed by time, whatever order they are listed in.\n"
        "# [[acquisition]]\n"
        "# path = \"acq_0.ply\"              # (required) PLY mesh with per-vertex sensor position\n"
        "# time = \"2026-01-05T10:00:00Z\"   # (required) ISO 8601 date-time with zone, or a date\n"
        "# name = \"january\"                # label in reports (default: the file name)\n"
        "# withdrawn = true                # a faulty pass: read as empty, no later pass renumbered\n";
  }
  for (const AcquisitionEntry* a : tables_in(c, order)) {
    out += fmt::format("\n[[acquisition]]\npath = {}\ntime = {}\nname = {}\n", toml_string(a->path.string()),
                       toml_string(format_iso8601(a->time)), toml_string(a->name));
    if (a->withdrawn) out += "withdrawn = true\n";
  }
  return out;
}

}  // namespace

Crs Config::crs() const {
  return Crs::parse(project.crs, parse_vertical_datum(project.vertical_datum, project.geoid_undulation));
}

std::vector<Acquisition> Config::acquisition_list() const {
  std::vector<Acquisition> list;
  for (std::size_t i = 0; i < acquisitions.size(); ++i) {
    list.push_back(
        {static_cast<std::uint32_t>(i), acquisitions[i].time, acquisitions[i].path, acquisitions[i].withdrawn});
  }
  return list;
}

std::vector<std::int32_t> Config::listed_indices() const {
  std::vector<std::int32_t> out;
  for (const AcquisitionEntry& a : acquisitions) out.push_back(static_cast<std::int32_t>(a.listed));
  return out;
}

std::vector<std::size_t> Config::listed_order() const {
  std::vector<std::size_t> order(acquisitions.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  // Stable: a config built by hand may leave every place 0.
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return acquisitions[a].listed < acquisitions[b].listed; });
  return order;
}

PlyReadParams Config::ply_read_params() const {
  PlyReadParams p;
  p.sensor_origin_names = input.sensor_origin;
  p.time_names = input.time;
  p.intensity_name = input.intensity;
  return p;
}

Config parse_config(std::string_view text, const std::filesystem::path& source, const ConfigLoadParams& params) {
  return Parser(source, params).parse(text);
}

Config load_config(const std::filesystem::path& file, const ConfigLoadParams& params) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(fmt::format("{}: cannot open config file", file.string()));
  std::ostringstream text;
  text << in.rdbuf();
  return parse_config(text.str(), file, params);
}

std::string dump_default_config() { return render(Config{}, true, TableOrder::listed); }

std::string effective_config_toml(const Config& config, TableOrder order) { return render(config, false, order); }

}  // namespace citymesh
