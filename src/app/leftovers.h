// SPDX-License-Identifier: MIT
// What killed runs leave in the work and output folders: nothing takes it for finished work,
// but a city's pair folder alone is 0.7 GB.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string_view>

#include "citymesh/config/config.h"

namespace citymesh::app {

/// The process tag ("<host>.<pid>") in the name of an entry that only a running process uses:
/// AtomicFile's temporary files ("<name>.tmp.<tag>"), the final pass's pair folders
/// ("pairs.<tag>"), the tiler's staging folders ("staging/a<k>.<tag>"); empty for any other
/// entry. `parent` is the name of the folder holding the entry.
std::string_view process_tag_in_name(std::string_view name, std::string_view parent);

/// Removes, anywhere under `dir`, the entries process_tag_in_name() recognises whose process
/// ran on this machine and has ended (killed, or crashed). Entries of running processes and of
/// other machines (a cluster's shared folder) are left. Best effort: what cannot be removed is
/// logged and left. Returns how many entries were removed.
std::size_t remove_leftovers_of_ended_runs(const std::filesystem::path& dir);

/// remove_leftovers_of_ended_runs() on the project's work and output folders: the commands
/// that write there call it first, so that a killed run's files go when the next run starts.
void remove_leftovers_of_ended_runs(const Config& config);

}  // namespace citymesh::app
