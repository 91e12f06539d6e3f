// SPDX-License-Identifier: MIT
// Doubles and boxes in the JSON files MPI ranks hand each other, as their bits: a box or a
// frame must come back exactly (an empty box is infinite, and a sum over ranks must equal one
// process's).
#pragma once

#include <nlohmann/json.hpp>

#include "citymesh/core/vec.h"

namespace citymesh::app {

nlohmann::json double_bits(double v);
double double_from_bits(const nlohmann::json& j);

nlohmann::json box_bits(const Box3d& b);
Box3d box_from_bits(const nlohmann::json& j);

}  // namespace citymesh::app
