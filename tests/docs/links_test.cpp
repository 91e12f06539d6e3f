// SPDX-License-Identifier: MIT
// Every relative link of README.md and docs/*.md leads somewhere: its file exists and its
// #anchor names a heading of that file (GitHub's rule: lower case, punctuation other than
// '-' and '_' dropped, spaces as '-'). Pages get split and sections renamed; a reader should
// not land on nothing.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.h"

namespace citymesh {
namespace {

/// The anchor GitHub gives a heading's text.
std::string slug(const std::string& heading) {
  std::string out;
  for (const char c : heading) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x80 || std::isalnum(u) != 0 || c == '-' || c == '_') {
      out += static_cast<char>(std::tolower(u));
    } else if (c == ' ') {
      out += '-';
    }
  }
  return out;
}

std::set<std::string> anchors_of(const std::filesystem::path& page) {
  std::set<std::string> anchors;
  std::istringstream in(test::read_text(page));
  bool fenced = false;
  for (std::string line; std::getline(in, line);) {
    if (line.starts_with("```")) fenced = !fenced;
    if (fenced || !line.starts_with("#")) continue;
    const std::size_t text = line.find_first_not_of('#');
    if (text == std::string::npos || line[text] != ' ') continue;
    anchors.insert(slug(line.substr(text + 1)));
  }
  return anchors;
}

std::vector<std::filesystem::path> pages() {
  std::vector<std::filesystem::path> out{test::source_dir() / "README.md"};
  for (const auto& entry : std::filesystem::directory_iterator(test::source_dir() / "docs")) {
    if (entry.path().extension() == ".md") out.push_back(entry.path());
  }
  return out;
}

/// The targets of the Markdown links "[text](target)" of `text`. (Not std::regex: GCC 12
/// warns inside it under -O2 with the sanitizers.)
std::vector<std::string> link_targets(const std::string& text) {
  std::vector<std::string> targets;
  for (std::size_t at = text.find("]("); at != std::string::npos; at = text.find("](", at + 2)) {
    const std::size_t begin = at + 2, end = text.find_first_of(") \t\n", begin);
    if (end != std::string::npos && text[end] == ')' && end > begin) targets.push_back(text.substr(begin, end - begin));
  }
  return targets;
}

TEST(DocsLinks, EveryRelativeLinkFindsItsFileAndHeading) {
  std::size_t checked = 0;
  std::map<std::filesystem::path, std::set<std::string>> anchors;  // per page linked to, read once
  for (const std::filesystem::path& page : pages()) {
    for (const std::string& target : link_targets(test::read_text(page))) {
      if (target.find("://") != std::string::npos || target.starts_with("mailto:")) continue;
      const std::size_t hash = target.find('#');
      const std::string file = target.substr(0, hash);
      const std::filesystem::path path = file.empty() ? page : page.parent_path() / file;
      ++checked;
      ASSERT_TRUE(std::filesystem::exists(path)) << page.filename() << ": " << target << ": no such file";
      if (hash == std::string::npos || path.extension() != ".md") continue;
      const auto [it, added] = anchors.try_emplace(path.lexically_normal());
      if (added) it->second = anchors_of(path);
      EXPECT_TRUE(it->second.contains(target.substr(hash + 1)))
          << page.filename() << ": " << target << ": no such heading in " << path.filename();
    }
  }
  EXPECT_GT(checked, 20u);  // the pages do link to each other
}

TEST(DocsLinks, LinksAreFoundAsMarkdownWritesThem) {
  EXPECT_EQ(link_targets("see [a](b.md#c), [d](e) and [not a link] (f) or [g](h i)"),
            (std::vector<std::string>{"b.md#c", "e"}));
}

TEST(DocsLinks, HeadingsGiveGithubsAnchors) {
  EXPECT_EQ(slug("Resume and `--force`"), "resume-and---force");
  EXPECT_EQ(slug("Hole fill (`fill_holes`, default on)"), "hole-fill-fill_holes-default-on");
  EXPECT_EQ(slug("Appending an acquisition (the monthly update)"), "appending-an-acquisition-the-monthly-update");
}

}  // namespace
}  // namespace citymesh
