// The light-probe sections (pack_format.h, "Light probes") as PackView::open reads them: a valid
// pack's accessors, truncation at every byte, flipped bytes refused or safe to use, and one
// targeted refusal per rule (missing sections, records, grid, sets, entries).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "lightpatch/light_probes.h"
#include "lightpatch/pack_view.h"
#include "runtime/pack_checks.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch {
namespace {

using testing::make_synthetic_pack;
using testing::open_message;
using testing::SyntheticOptions;
using testing::SyntheticPack;

SyntheticOptions probe_options(uint32_t seed = 1) {
  return testing::with_probe_grid(SyntheticOptions(), 3, 2, 2, seed);
}

TEST(ProbeValidation, APackWithProbesOpensAndShowsThem) {
  PackView v;
  const SyntheticPack bytes = make_synthetic_pack(probe_options());
  ASSERT_EQ(open_message(bytes, &v), "");
  ASSERT_TRUE(v.has_probe_grid());
  EXPECT_EQ(v.probe_grid_point_count(), 12u);
  EXPECT_EQ(v.probe_grid().size[0], 3u);
  EXPECT_FLOAT_EQ(v.probe_grid().spacing, 0.5f);
  uint32_t on_grid = 0;
  for (uint32_t k = 0; k < v.probe_grid_point_count(); ++k) {
    const uint32_t p = v.probe_grid_indices()[k];
    if (p == pack::kNone32) continue;
    ++on_grid;
    ASSERT_LT(p, v.probe_count());
    EXPECT_EQ(v.probe_name(p).length, 0u);
    const float x = v.probe_grid().origin[0] + 0.5f * float(k % 3);
    EXPECT_FLOAT_EQ(v.probe(p).position[0], x);
  }
  EXPECT_EQ(v.probe_count(), on_grid + 2);  // two named probes
  EXPECT_EQ(v.find_probe("probe_1", 7), int32_t(on_grid + 1));
  EXPECT_EQ(v.find_probe("probe_9", 7), -1);
  EXPECT_EQ(v.find_probe("", 0), -1);
  ASSERT_GT(v.probe_set_count(), 1u + v.light_count());  // base, contributions, shadows
  EXPECT_EQ(v.probe_set(0).kind, pack::kGroupBase);
  EXPECT_EQ(v.probe_set(0).entry_count, v.probe_count());  // the base reaches every probe
  uint32_t covered = 0;
  for (uint32_t s = 0; s < v.probe_set_count(); ++s) covered += v.probe_set(s).entry_count;
  EXPECT_EQ(covered, v.probe_entry_count());
  EXPECT_EQ(v.probe_bytes(), uint64_t(v.probe_count()) * 48 + 32 + 12 * 4 +
                                 uint64_t(v.probe_set_count()) * 16 +
                                 uint64_t(v.probe_entry_count()) * 112);

  // Without probes: nothing, and no sections.
  PackView plain;
  ASSERT_EQ(open_message(make_synthetic_pack(SyntheticOptions()), &plain), "");
  EXPECT_EQ(plain.probe_count(), 0u);
  EXPECT_FALSE(plain.has_probe_grid());
  EXPECT_EQ(plain.probe_set_count(), 0u);
  EXPECT_EQ(plain.probe_bytes(), 0u);
}

// Golden values of probes.lpk (format version 7 with light probes, a grid and named probes).
constexpr uint64_t kProbesSize = 30720;
constexpr uint32_t kProbesCrc = 0x78811239u;

// Keeps the committed pack byte-equal to what the builder writes (committed_pack.h).
TEST(ProbeValidation, GoldenBytesOfAPackWithProbes) {
  const SyntheticPack built = make_synthetic_pack(probe_options(2));
  const uint8_t* b = reinterpret_cast<const uint8_t*>(built.data());
  testing::expect_committed_pack(b, built.size, "probes.lpk", kProbesSize, kProbesCrc);
  // Pinned offsets: a probe's reach, a set's first entry, an entry's first coefficient.
  PackView v;
  ASSERT_EQ(open_message(built, &v), "");
  const uint8_t* probe = reinterpret_cast<const uint8_t*>(&v.probe(0));
  float reach;
  std::memcpy(&reach, probe + 12, 4);
  EXPECT_EQ(reach, v.probe(0).reach[0]);
  const uint8_t* set = reinterpret_cast<const uint8_t*>(&v.probe_set(1));
  uint32_t first;
  std::memcpy(&first, set + 8, 4);
  EXPECT_EQ(first, v.probe_set(1).first_entry);
  const uint8_t* entry = reinterpret_cast<const uint8_t*>(&v.probe_entry(0));
  float sh0;
  std::memcpy(&sh0, entry + 4, 4);
  EXPECT_EQ(sh0, v.probe_entry(0).sh[0]);
  EXPECT_EQ(reinterpret_cast<const uint8_t*>(v.probe_grid_indices()) -
                reinterpret_cast<const uint8_t*>(&v.probe_grid()),
            32);
}

TEST(ProbeValidation, TruncatedAtEveryByteIsRefused) {
  const SyntheticPack bytes = make_synthetic_pack(probe_options(2));
  testing::expect_truncations_refused(bytes.data(), bytes.size);
}

// Uses every probe accessor and LightProbes on a view (ASan catches reads out of bounds).
void exercise(const PackView& v) {
  SceneState st;
  LightProbes probes;
  ASSERT_EQ(st.init(v, nullptr), Status::kOk);
  ASSERT_EQ(probes.init(v, nullptr), Status::kOk);
  ASSERT_EQ(probes.update(st), Status::kOk);
  float sh[kProbeShFloats];
  for (uint32_t p = 0; p < v.probe_count(); ++p) {
    probes.probe_sh(p, sh);
    (void)v.probe_name(p);
  }
  for (float x = -3.0f; x < 3.0f; x += 0.37f) {
    const float pos[3] = {x, 0.5f * x, -x};
    probes.sample(pos, sh);
  }
  (void)probes.find_probe("probe_0");
}

TEST(ProbeValidation, FlippedBytesInTheProbeSectionsAreRefusedOrSafe) {
  const SyntheticPack bytes = make_synthetic_pack(probe_options(3));
  const uint8_t* b = reinterpret_cast<const uint8_t*>(bytes.data());
  const std::vector<uint8_t> all(b, b + bytes.size);
  PackView original;
  ASSERT_TRUE(bytes.open(&original, nullptr));
  // The probe sections lie after the strings, at the end of the file.
  const uint64_t begin = uint64_t(reinterpret_cast<const uint8_t*>(&original.probe(0)) - b);
  const testing::FlipCounts n =
      testing::flip_bytes(all, begin, bytes.size, 3, [](const PackView& v) { exercise(v); });
  EXPECT_GT(n.refused_raw, 0);
  EXPECT_GT(n.refused_fixed, 0);
  EXPECT_GT(n.accepted, 0);  // e.g. a coefficient changed to another finite value
}

TEST(ProbeValidation, ProbeSectionsComeTogether) {
  for (uint32_t dropped : {pack::kSectionProbeSets, pack::kSectionProbeEntries}) {
    SyntheticOptions o = probe_options();
    o.drop_section = dropped;
    EXPECT_NE(open_message(make_synthetic_pack(o)).find("probes section without"),
              std::string::npos)
        << dropped;
  }
  SyntheticOptions o = probe_options();
  o.drop_section = pack::kSectionProbes;
  EXPECT_NE(open_message(make_synthetic_pack(o)).find("without a probes section"),
            std::string::npos);
  // The grid is optional.
  o.drop_section = pack::kSectionProbeGrid;
  PackView v;
  EXPECT_EQ(open_message(make_synthetic_pack(o), &v), "");
  EXPECT_FALSE(v.has_probe_grid());
}

using Probes = std::vector<pack::ProbeRecord>;
using Sets = std::vector<pack::ProbeSetRecord>;
using Entries = std::vector<pack::ProbeEntry>;
using Grid = std::vector<uint32_t>;

struct Refusal {
  const char* expected;  // part of the message
  std::function<void(Probes&, pack::ProbeGridRecord&, Grid&, Sets&, Entries&)> edit;
};

TEST(ProbeValidation, EachRuleIsEnforced) {
  const float nan = std::nanf("");
  const Refusal refusals[] = {
      {"probe 1: position is not finite",
       [&](Probes& p, auto&, auto&, auto&, auto&) { p[1].position[2] = nan; }},
      {"probe 0: reach 3 is not finite and >= 0",
       [](Probes& p, auto&, auto&, auto&, auto&) { p[0].reach[3] = -0.5f; }},
      {"probe 2: unnamed with a name offset",
       [](Probes& p, auto&, auto&, auto&, auto&) { p[2].name_offset = 1; }},
      {"exceeds the string section",
       [](Probes& p, auto&, auto&, auto&, auto&) { p.back().name_length = 100000; }},
      {"probe 0: reserved", [](Probes& p, auto&, auto&, auto&, auto&) { p[0].reserved = 1; }},
      {"probe grid: spacing",
       [](auto&, pack::ProbeGridRecord& g, auto&, auto&, auto&) { g.spacing = 0.0f; }},
      {"probe grid: origin",
       [&](auto&, pack::ProbeGridRecord& g, auto&, auto&, auto&) { g.origin[1] = INFINITY; }},
      {"has an empty axis",
       [](auto&, pack::ProbeGridRecord& g, auto&, auto&, auto&) { g.size[2] = 0; }},
      {"over the limit",
       [](auto&, pack::ProbeGridRecord& g, auto&, auto&, auto&) {
         g.size[0] = g.size[1] = g.size[2] = 0x80000000u;  // a product of 2^93 points
       }},
      {"expected 80 for 12 grid points",
       [](auto&, auto&, Grid& grid, auto&, auto&) { grid.pop_back(); }},
      {"probe grid: point 4 names probe",
       [](Probes& p, auto&, Grid& grid, auto&, auto&) { grid[4] = uint32_t(p.size()); }},
      {"kind 3 (pair correction) has no probe sets",
       [](auto&, auto&, auto&, Sets& s, auto&) { s[1].kind = pack::kGroupPairCorrection; }},
      {"probe set 1 (contribution): owner light",
       [](auto&, auto&, auto&, Sets& s, auto&) { s[1].object_a = 0; }},
      {"probe set 0 (base): owner", [](auto&, auto&, auto&, Sets& s, auto&) { s[0].light = 0; }},
      {"probe set 2: not sorted",
       [](auto&, auto&, auto&, Sets& s, auto&) { std::swap(s[1].light, s[2].light); }},
      {"probe set 1: no entries",
       [](auto&, auto&, auto&, Sets& s, auto&) {
         s[2].first_entry = s[1].first_entry;
         s[2].entry_count += s[1].entry_count;
         s[1].entry_count = 0;
       }},
      {"probe set 2: first entry",
       [](auto&, auto&, auto&, Sets& s, auto&) { s[2].first_entry += 1; }},
      {"probe sets cover", [](auto&, auto&, auto&, auto&, Entries& e) { e.push_back(e.back()); }},
      {"probe entry 3: probe",
       [](Probes& p, auto&, auto&, auto&, Entries& e) { e[3].probe = uint32_t(p.size()); }},
      {"probe entry 3: probe 2 not after probe 3",
       [](auto&, auto&, auto&, auto&, Entries& e) { std::swap(e[2].probe, e[3].probe); }},
      {"probe entry 5: SH coefficient not finite",
       [&](auto&, auto&, auto&, auto&, Entries& e) { e[5].sh[26] = nan; }},
  };
  for (const Refusal& r : refusals) {
    SyntheticOptions o = probe_options();
    o.probe_hole_probability = 0.0f;
    o.mutate_probes = r.edit;
    const std::string message = open_message(make_synthetic_pack(o));
    EXPECT_NE(message.find(r.expected), std::string::npos)
        << "expected \"" << r.expected << "\", got \"" << message << "\"";
  }
}

}  // namespace
}  // namespace lightpatch
