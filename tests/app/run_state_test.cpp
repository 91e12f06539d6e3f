// SPDX-License-Identifier: MIT
// The work folder's record of its config: what resumes, what is refused, and which
// fingerprints an appended acquisition leaves alone.
#include "run_state.h"

#include <gtest/gtest.h>

#include <map>
#include <string>

#include "citymesh/core/error.h"
#include "test_support.h"

namespace citymesh::app {
namespace {

using Keys = std::map<std::string, std::string>;

/// The keys of a run of `n` acquisitions (dates one month apart).
Keys keys_of(std::size_t n) {
  Keys keys{{"change.distance_threshold", "0.1"}, {"tiling.tile_size", "50"}, {"input.time_base", "\"gps-week\""}};
  for (std::size_t k = 0; k < n; ++k) {
    const std::string a = "acquisition[" + std::to_string(k) + "]";
    keys[a + ".path"] = "/data/pass" + std::to_string(k) + ".ply";
    keys[a + ".file"] = std::to_string(1000 + k) + " bytes, modified 42";
    keys[a + ".time"] = "2026-0" + std::to_string(k + 1) + "-01T10:00:00Z";
  }
  return keys;
}

/// What check_run_config says when it refuses `keys` in `work` (nothing when it resumes:
/// then the test fails, saying `what` should have been refused).
std::string refusal(const test::TempDir& work, const Keys& keys, const char* what) {
  try {
    check_run_config(work.path(), keys, false);
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << what;
  return {};
}

TEST(RunState, AcquisitionsAppendedOrRemovedResumeAndOneChangedIsRefused) {
  test::TempDir work;
  check_run_config(work.path(), keys_of(3), false);
  EXPECT_NO_THROW(check_run_config(work.path(), keys_of(3), false));
  EXPECT_NO_THROW(check_run_config(work.path(), keys_of(6), false)) << "three passes appended";
  EXPECT_NO_THROW(check_run_config(work.path(), keys_of(4), false)) << "the last two withdrawn: none renumbered";
  // A pass removed before the last one renumbers those after it, by time: input too (their
  // tiles are redone), as a pass delivered late is.
  Keys middle = keys_of(3);
  middle["acquisition[1].path"] = "/data/pass2.ply";
  middle["acquisition[1].file"] = keys_of(3)["acquisition[2].file"];
  middle["acquisition[1].time"] = keys_of(3)["acquisition[2].time"];
  middle["acquisition[2].path"] = "/data/pass3.ply";
  middle["acquisition[2].file"] = keys_of(4)["acquisition[3].file"];
  middle["acquisition[2].time"] = keys_of(4)["acquisition[3].time"];
  EXPECT_NO_THROW(check_run_config(work.path(), middle, false)) << "a pass removed in the middle";
  EXPECT_NO_THROW(check_run_config(work.path(), keys_of(4), false)) << "and put back";
  // Removed while another pass changed: refused, naming the change.
  Keys middle_changed = middle;
  middle_changed["acquisition[0].path"] = "/data/other.ply";
  const std::string middle_changed_refused =
      refusal(work, middle_changed, "a pass removed in the middle, another one changed");
  EXPECT_NE(middle_changed_refused.find("acquisition[0].path"), std::string::npos) << middle_changed_refused;
  Keys changed = keys_of(6);
  changed["acquisition[1].time"] = "2026-02-02T10:00:00Z";
  const std::string changed_refused = refusal(work, changed, "an existing pass's date changed beside an appended one");
  EXPECT_NE(changed_refused.find("acquisition[1].time"), std::string::npos) << changed_refused;
  EXPECT_EQ(changed_refused.find("acquisition[5]"), std::string::npos) << changed_refused;
  // A pass inserted before the last one renumbers it: its keys change.
  check_run_config(work.path(), keys_of(5), false);
  Keys inserted = keys_of(5);
  inserted["acquisition[4].path"] = "/data/inserted.ply";
  inserted["acquisition[5].path"] = "/data/pass4.ply";
  inserted["acquisition[5].file"] = keys_of(5)["acquisition[4].file"];
  inserted["acquisition[5].time"] = "2026-07-01T10:00:00Z";
  EXPECT_THROW(check_run_config(work.path(), inserted, false), ConfigError);
  // A rewritten file is not refused; --force takes anything.
  Keys rewritten = keys_of(5);
  rewritten["acquisition[0].file"] = "1000 bytes, modified 43";
  EXPECT_NO_THROW(check_run_config(work.path(), rewritten, false));
  EXPECT_NO_THROW(check_run_config(work.path(), keys_of(2), true));
}

/// `keys` with a pass of `time` inserted at place `at` (numbered by time), the later ones moved
/// up one.
Keys with_inserted(const Keys& keys, std::size_t passes, std::size_t at, const std::string& time) {
  Keys out;
  for (const auto& [k, v] : keys) {
    if (!k.starts_with("acquisition[")) out[k] = v;
  }
  for (std::size_t k = 0; k <= passes; ++k) {
    const std::string to = "acquisition[" + std::to_string(k) + "]";
    if (k == at) {
      out[to + ".path"] = "/data/late.ply";
      out[to + ".file"] = "999 bytes, modified 42";
      out[to + ".time"] = time;
      continue;
    }
    const std::string from = "acquisition[" + std::to_string(k < at ? k : k - 1) + "]";
    for (const char* key : {".path", ".file", ".time"}) out[to + key] = keys.at(from + key);
  }
  return out;
}

TEST(RunState, APassDeliveredLateResumesThoughTheLaterPassesAreRenumbered) {
  test::TempDir work;
  check_run_config(work.path(), keys_of(3), false);
  // An older pass delivered after the others: processed by time, second.
  const Keys late = with_inserted(keys_of(3), 3, 1, "2026-01-15T10:00:00Z");
  EXPECT_NO_THROW(check_run_config(work.path(), late, false));
  // The same with a setting changed too: refused, for the setting alone.
  Keys changed = with_inserted(late, 4, 4, "2026-09-01T10:00:00Z");
  changed["change.distance_threshold"] = "0.2";
  const std::string changed_refused = refusal(work, changed, "a setting changed beside a pass delivered late");
  EXPECT_NE(changed_refused.find("change.distance_threshold"), std::string::npos) << changed_refused;
  EXPECT_EQ(changed_refused.find("acquisition["), std::string::npos) << changed_refused;
  // A pass inserted while another one's date changed: not only passes added, refused.
  Keys redated = with_inserted(late, 4, 0, "2025-12-01T10:00:00Z");
  redated["acquisition[4].time"] = "2026-04-02T10:00:00Z";
  EXPECT_THROW(check_run_config(work.path(), redated, false), ConfigError);
}

TEST(RunState, APassWithdrawnInPlaceOrPutBackResumesAndChangesOnlyItsOwnFingerprint) {
  test::TempDir work;
  check_run_config(work.path(), keys_of(3), false);
  Keys withdrawn = keys_of(3);  // as result_keys gives them for `withdrawn = true`
  withdrawn["acquisition[1].withdrawn"] = "true";
  withdrawn["acquisition[1].file"] = "withdrawn";
  EXPECT_NO_THROW(check_run_config(work.path(), withdrawn, false));
  EXPECT_NO_THROW(check_run_config(work.path(), keys_of(3), false)) << "put back";
  const RunFingerprints before = run_fingerprints(keys_of(3), 3), after = run_fingerprints(withdrawn, 3);
  EXPECT_EQ(before.settings, after.settings);
  EXPECT_EQ(before.acquisitions[0], after.acquisitions[0]);
  EXPECT_NE(before.acquisitions[1], after.acquisitions[1]) << "its tiling is made again (empty)";
  EXPECT_EQ(before.acquisitions[2], after.acquisitions[2]);
  // Its date or path changed at the same time is still a change of config.
  withdrawn["acquisition[1].time"] = "2026-02-03T10:00:00Z";
  EXPECT_THROW(check_run_config(work.path(), withdrawn, false), ConfigError);
}

TEST(RunState, AFileNamedByItsAbsolutePathBeforeAndRelativeNowIsTheSameFile) {
  test::TempDir work;
  Keys before = keys_of(2);
  before["acquisition[1].path"] = "/data/city/pass1.ply";
  check_run_config(work.path(), before, false);
  Keys now = before;
  now["acquisition[1].path"] = "pass1.ply";  // under the config's folder, /data/city
  EXPECT_NO_THROW(check_run_config(work.path(), now, false));
  for (const char* name : {"pass2.ply", "ass1.ply", "city/pass2.ply"}) {
    check_run_config(work.path(), before, true);  // recorded by absolute path again
    Keys other = before;
    other["acquisition[1].path"] = name;
    EXPECT_THROW(check_run_config(work.path(), other, false), ConfigError) << name << ": another file";
  }
}

TEST(RunState, AppendingAnAcquisitionKeepsTheOtherFingerprints) {
  const RunFingerprints three = run_fingerprints(keys_of(3), 3), four = run_fingerprints(keys_of(4), 4);
  EXPECT_EQ(three.settings, four.settings);
  ASSERT_EQ(four.acquisitions.size(), 4u);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(three.acquisitions[k], four.acquisitions[k]) << k;
  EXPECT_NE(four.acquisitions[3], four.acquisitions[2]);
  EXPECT_NE(three.store, four.store);
  // A rewritten file changes its own acquisition's fingerprint only.
  Keys rewritten = keys_of(3);
  rewritten["acquisition[1].file"] = "1001 bytes, modified 43";
  const RunFingerprints r = run_fingerprints(rewritten, 3);
  EXPECT_EQ(r.settings, three.settings);
  EXPECT_EQ(r.acquisitions[0], three.acquisitions[0]);
  EXPECT_NE(r.acquisitions[1], three.acquisitions[1]);
  EXPECT_EQ(r.acquisitions[2], three.acquisitions[2]);
  // A tiling key changes every acquisition's tiling; a change key only the settings.
  Keys tiling = keys_of(3), change = keys_of(3);
  tiling["tiling.tile_size"] = "40";
  change["change.distance_threshold"] = "0.2";
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NE(run_fingerprints(tiling, 3).acquisitions[k], three.acquisitions[k]);
    EXPECT_EQ(run_fingerprints(change, 3).acquisitions[k], three.acquisitions[k]);
  }
  EXPECT_NE(run_fingerprints(change, 3).settings, three.settings);
  // acquisition[10] is the eleventh acquisition, not the second.
  const RunFingerprints eleven = run_fingerprints(keys_of(11), 11);
  EXPECT_EQ(eleven.acquisitions[1], three.acquisitions[1]);
  EXPECT_NE(eleven.acquisitions[10], eleven.acquisitions[1]);
}

}  // namespace
}  // namespace citymesh::app
