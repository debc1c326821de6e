// The inn generator: determinism, counts, names, semi-dynamic markings, sidecars, validation.
#include <cmath>
#include <map>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "gltf_test_util.h"
#include "inn_generator.h"

namespace lightpatch::inn {
namespace {

using nlohmann::json;

struct Summary {
  std::size_t triangles = 0;
  std::size_t semi_lights = 0;
  std::size_t static_lights = 0;
  std::size_t semi_objects = 0;
  std::set<std::string> names;
  std::set<std::string> light_nodes;
  std::set<std::string> object_nodes;
  bool names_unique = true;
  bool every_semi_light_has_radius = true;
  std::set<std::string> moving_lights;  // extras.moving (semi-dynamic too)
};

// Counts from the written file itself (not from the generator's own statistics).
Summary summarize(const json& j) {
  Summary s;
  std::vector<std::size_t> mesh_tris;
  for (const auto& mesh : j["meshes"]) {
    std::size_t t = 0;
    for (const auto& prim : mesh["primitives"])
      t += j["accessors"][prim["indices"].get<int>()]["count"].get<std::size_t>() / 3;
    mesh_tris.push_back(t);
  }
  for (const auto& n : j["nodes"]) {
    const std::string name = n["name"];
    s.names_unique = s.names.insert(name).second && s.names_unique;
    if (n.contains("mesh")) s.triangles += mesh_tris[n["mesh"].get<std::size_t>()];
    const bool semi = n.contains("extras") && n["extras"].value("semiDynamic", false);
    if (n.contains("extensions") && n["extensions"].contains("KHR_lights_punctual")) {
      s.light_nodes.insert(name);
      if (n.contains("extras") && n["extras"].value("moving", false)) s.moving_lights.insert(name);
      if (semi) {
        ++s.semi_lights;
        s.every_semi_light_has_radius =
            s.every_semi_light_has_radius && n["extras"].value("lightRadius", 0.0) > 0.0;
      } else {
        ++s.static_lights;
      }
    } else if (semi) {
      ++s.semi_objects;
      s.object_nodes.insert(name);
    }
  }
  return s;
}

json load_json(const std::filesystem::path& p) {
  return json::parse(test::slurp(p));
}

TEST(InnGenerator, SmallIsDeterministicAndSeedsDiffer) {
  const InnOptions small{InnScale::kSmall, 7};
  EXPECT_EQ(generate_inn(small).scene.to_glb(), generate_inn(small).scene.to_glb());
  EXPECT_EQ(generate_inn(small).scene.to_glb({.draco = true}),
            generate_inn(small).scene.to_glb({.draco = true}));
  EXPECT_NE(generate_inn(small).scene.to_glb(), generate_inn({InnScale::kSmall, 8}).scene.to_glb());
  EXPECT_EQ(generate_inn(small).scenario.dump(), generate_inn(small).scenario.dump());
}

TEST(InnGenerator, FullWrittenTwiceGivesIdenticalFiles) {
  const auto dir = test::scratch_dir();
  write_inn(generate_inn({InnScale::kFull, 1}), (dir / "a.glb").string(), false);
  write_inn(generate_inn({InnScale::kFull, 1}), (dir / "b.glb").string(), false);
  EXPECT_EQ(test::read_file(dir / "a.glb"), test::read_file(dir / "b.glb"));
  EXPECT_EQ(test::read_file(dir / "a.state.json"), test::read_file(dir / "b.state.json"));
  std::filesystem::remove_all(dir);
}

void check_inn(InnScale scale, std::size_t min_tris, std::size_t max_tris,
               std::size_t min_semi_lights, std::size_t min_items) {
  const Inn inn = generate_inn({scale, 1});
  const test::Glb glb = test::parse_glb(inn.scene.to_glb());
  const Summary s = summarize(glb.json);
  EXPECT_TRUE(s.names_unique);
  EXPECT_EQ(s.triangles, inn.stats.triangles);
  EXPECT_GE(s.triangles, min_tris);
  EXPECT_LE(s.triangles, max_tris);
  EXPECT_EQ(s.semi_lights, inn.stats.semi_dynamic_lights + inn.stats.moving_lights);
  // The lantern: the one moving light, lit on its hook.
  EXPECT_EQ(inn.stats.moving_lights, 1u);
  EXPECT_EQ(s.moving_lights, std::set<std::string>{"lantern"});
  EXPECT_EQ(inn.scenario["lantern"], "lantern");
  EXPECT_FALSE(inn.state["lights"].contains("lantern"));
  EXPECT_GE(s.semi_lights, min_semi_lights);
  EXPECT_TRUE(s.every_semi_light_has_radius);
  EXPECT_EQ(s.static_lights, inn.stats.static_lights);
  EXPECT_GE(s.static_lights, 2u);  // moonlight and a hearth ember keep the base map lit
  // Objects: the spell book, the items and one placed_ copy of each.
  EXPECT_GE(inn.stats.items, min_items);
  EXPECT_EQ(s.semi_objects, 1 + 2 * inn.stats.items);
  EXPECT_TRUE(s.object_nodes.count("spell_book"));
  for (const auto& item_json : inn.scenario["items"]) {
    const std::string item = item_json.get<std::string>();
    EXPECT_TRUE(s.object_nodes.count(item)) << item;
    EXPECT_TRUE(s.object_nodes.count("placed_" + item)) << item;
    // Placed copies start hidden.
    EXPECT_EQ(inn.state["objects"]["placed_" + item]["visible"], false) << item;
  }
  // No TEXCOORD_1 (the cooker unwraps); every light the state names exists; most start off.
  for (const auto& mesh : glb.json["meshes"]) {
    for (const auto& prim : mesh["primitives"])
      EXPECT_FALSE(prim["attributes"].contains("TEXCOORD_1"));
  }
  std::size_t off = 0;
  for (const auto& [name, l] : inn.state["lights"].items()) {
    EXPECT_TRUE(s.light_nodes.count(name)) << name;
    off += l["on"] == false ? 1u : 0u;
  }
  EXPECT_GT(2 * off, s.semi_lights);
  for (const auto& [name, o] : inn.state["objects"].items())
    EXPECT_TRUE(s.object_nodes.count(name)) << name;
  // Scenario: every step names a node of the scene; each off light is lit once, besides the
  // close-ups with the carried item (a candle beside it snuffed and lit again, then a candle of
  // another room); ends with the spell.
  const json& steps = inn.scenario["steps"];
  ASSERT_GE(steps.size(), 3u);
  std::size_t lit = 0, placed = 0, close_ups = 0, carried = 0, moves = 0;
  json last_pose;
  for (const auto& step : steps) {
    // The lantern walk: taken, then moved in steps of at most 2.5 m (positions in the state).
    carried += step["action"] == "carry" ? 1u : 0u;
    if (step["action"] == "move") {
      ++moves;
      EXPECT_EQ(carried, 1u);
      EXPECT_GE(step.value("frames", 0), 1);  // carried over frames, at a walk
      const json& pose = step["state"]["lights"]["lantern"]["position"];
      ASSERT_EQ(pose.size(), 3u);
      if (!last_pose.is_null()) {
        double d2 = 0;
        for (size_t a = 0; a < 3; ++a) {
          const double d = pose[a].get<double>() - last_pose[a].get<double>();
          d2 += d * d;
        }
        EXPECT_LE(std::sqrt(d2), 2.5);
      }
      last_pose = pose;
    }
    if (step.contains("node")) {
      EXPECT_TRUE(s.names.count(step["node"].get<std::string>())) << step.dump();
    }
    const bool close_up = step.contains("held_item");
    if (close_up) {
      EXPECT_EQ(step["action"], "light");
      EXPECT_TRUE(step.value("close_up", false));
    }
    close_ups += close_up ? 1u : 0u;
    lit += step["action"] == "light" && !close_up ? 1u : 0u;
    placed += step["action"] == "place" ? 1u : 0u;
  }
  EXPECT_EQ(lit, off);
  EXPECT_EQ(close_ups, 4u);
  EXPECT_EQ(placed, inn.stats.items);
  EXPECT_EQ(carried, 1u);
  EXPECT_EQ(moves, 5u);
  EXPECT_EQ(steps.front()["action"], "start");
  EXPECT_EQ(steps.back()["action"], "spell_done");
}

TEST(InnGenerator, SmallCounts) {
  check_inn(InnScale::kSmall, 5000, 10000, 4, 2);
}

TEST(InnGenerator, FullCounts) {
  check_inn(InnScale::kFull, 215000, 235000, 12, 6);
}

TEST(InnGenerator, FullHasTheRooms) {
  const Inn inn = generate_inn({InnScale::kFull, 1});
  const test::Glb glb = test::parse_glb(inn.scene.to_glb());
  const Summary s = summarize(glb.json);
  for (const char* room : {"room_dining", "room_corridor", "room_bedroom_1", "room_bedroom_2",
                           "room_cellar", "room_living_main", "room_living_small", "room_bath"}) {
    EXPECT_TRUE(s.names.count(room)) << room;
  }
  // Spot lights (the fires) and a directional moon are present.
  std::map<std::string, int> types;
  for (const auto& l : glb.json["extensions"]["KHR_lights_punctual"]["lights"])
    ++types[l["type"].get<std::string>()];
  EXPECT_GE(types["spot"], 2);
  EXPECT_EQ(types["directional"], 1);
  EXPECT_GE(types["point"], 12);
}

TEST(InnGenerator, WritesSidecarsBesideTheScene) {
  const auto dir = test::scratch_dir();
  const Inn inn = generate_inn({InnScale::kSmall, 1});
  write_inn(inn, (dir / "inn.glb").string(), true);
  ASSERT_TRUE(std::filesystem::exists(dir / "inn.state.json"));
  ASSERT_TRUE(std::filesystem::exists(dir / "inn.scenario.json"));
  EXPECT_EQ(state_path_for((dir / "inn.glb").string()), (dir / "inn.state.json").string());
  const json state = load_json(dir / "inn.state.json");
  EXPECT_TRUE(state.contains("lights"));
  EXPECT_TRUE(state.contains("objects"));
  const json scenario = load_json(dir / "inn.scenario.json");
  EXPECT_EQ(scenario["scene"], "inn.glb");
  EXPECT_EQ(scenario["initial_state"], "inn.state.json");
  std::filesystem::remove_all(dir);
}

// The Khronos validator must accept every variant with no errors. It must be installed (see
// tests/inn/CMakeLists.txt); a missing validator fails these tests.
void validate(InnScale scale, bool draco) {
  const auto dir = test::scratch_dir();
  const auto file = dir / "inn.glb";
  write_inn(generate_inn({scale, 1}), file.string(), draco);
  const int rc = test::run_validator(file);
  EXPECT_EQ(rc, 0) << test::slurp(file.string() + ".log");
  if (rc == 0) {
    const json report = load_json(file.string() + ".report.json");
    EXPECT_EQ(report["issues"]["numErrors"], 0);
    EXPECT_EQ(report["issues"]["numWarnings"], 0);
    std::filesystem::remove_all(dir);
  }
}

TEST(InnValidator, SmallPlain) {
  validate(InnScale::kSmall, false);
}
TEST(InnValidator, SmallDraco) {
  validate(InnScale::kSmall, true);
}
TEST(InnValidator, FullPlain) {
  validate(InnScale::kFull, false);
}
TEST(InnValidator, FullDraco) {
  validate(InnScale::kFull, true);
}

}  // namespace
}  // namespace lightpatch::inn
