// SPDX-License-Identifier: MIT
// Every malformed file in tests/data/bad (listed with its expectation in cases.tsv) must give
// the right error class, exit code and message, in-process and through the citymesh binary.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "citymesh/config/config.h"
#include "citymesh/core/error.h"
#include "citymesh/io/ply_inspect.h"
#include "test_support.h"

namespace citymesh {
namespace {

struct BadCase {
  std::string file, command, kind, fragment;
  int exit_code = 0;
};

std::vector<BadCase> load_cases() {
  std::ifstream in(test::source_dir() / "tests/data/bad/cases.tsv");
  std::vector<BadCase> cases;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    BadCase c;
    std::string code;
    std::getline(fields, c.file, '\t');
    std::getline(fields, c.command, '\t');
    std::getline(fields, c.kind, '\t');
    std::getline(fields, code, '\t');
    std::getline(fields, c.fragment, '\t');
    c.exit_code = std::stoi(code);
    cases.push_back(c);
  }
  return cases;
}

std::filesystem::path bad_dir() { return test::source_dir() / "tests/data/bad"; }

/// Runs the library call that the command makes; returns the exception it threw.
void call_library(const BadCase& c) {
  const auto path = bad_dir() / c.file;
  if (c.command == "check") {
    load_config(path);
  } else {
    const PlyInspection r = inspect_ply(path);
    if (c.command == "info-origin" && !r.layout.has_sensor_origin) {
      throw InputError(path.string() + ": no sensor position");
    }
  }
}

class BadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInput, LibraryThrowsTheRightClassWithContext) {
  const BadCase& c = GetParam();
  try {
    call_library(c);
    FAIL() << c.file << ": no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.kind()), c.kind) << e.what();
    EXPECT_EQ(static_cast<int>(e.exit_code()), c.exit_code) << e.what();
    EXPECT_NE(std::string(e.what()).find(c.file), std::string::npos) << "message must name the file: " << e.what();
  }
}

TEST_P(BadInput, CommandExitsWithTheRightCodeAndMessage) {
  const BadCase& c = GetParam();
  const std::string path = (bad_dir() / c.file).string();
  std::string args = c.command == "check" ? "config --check " + path
                     : c.command == "info-origin" ? "info --require-origin " + path
                                                  : "info " + path;
  const test::CommandResult r = test::run_citymesh(args);
  EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
  EXPECT_NE(r.err.find(c.kind + " error: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(c.fragment), std::string::npos) << "expected '" << c.fragment << "' in: " << r.err;
  EXPECT_TRUE(r.out.empty()) << "errors go to stderr, not stdout: " << r.out;
}

INSTANTIATE_TEST_SUITE_P(TestsDataBad, BadInput, ::testing::ValuesIn(load_cases()),
                         [](const ::testing::TestParamInfo<BadCase>& param_info) {
                           std::string name = param_info.param.file;
                           for (char& ch : name) {
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           }
                           return name;
                         });

TEST(BadInputTable, HasAtLeastThirtyCases) { EXPECT_GE(load_cases().size(), 30u); }

}  // namespace
}  // namespace citymesh
