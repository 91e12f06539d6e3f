// SPDX-License-Identifier: MIT
// The table of configuration keys: each key is declared once, with its meaning, range and
// how it reads and prints; parsing, --dump-defaults and the effective config all use it.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <toml++/toml.h>
#include <vector>

#include "citymesh/config/config.h"

namespace citymesh::config_detail {

/// Where a value came from, for error messages ("run.toml:12:3: change.halo: ...").
struct KeyContext {
  std::string where;
  [[noreturn]] void fail(std::string_view why) const;
};

struct KeyDef {
  std::string_view section;
  std::string_view name;
  std::string help;              ///< one line, with unit and range
  std::string_view example;      ///< required keys: a value to show
  std::function<void(Config&, const toml::node&, const KeyContext&)> read;
  std::function<std::string(const Config&)> show;  ///< TOML literal; "" while unset
  [[nodiscard]] bool required() const { return !example.empty(); }
  [[nodiscard]] std::string full_name() const { return std::string(section) + "." + std::string(name); }
};

/// Every key of every [section] (the [[acquisition]] array is handled on its own).
const std::vector<KeyDef>& config_keys();
/// Section names in the order they are documented.
const std::vector<std::string_view>& config_sections();
/// Keys of one [[acquisition]] table.
const std::vector<std::string_view>& acquisition_keys();

/// TOML spelling of a string (quoted and escaped).
std::string toml_string(std::string_view s);

}  // namespace citymesh::config_detail
