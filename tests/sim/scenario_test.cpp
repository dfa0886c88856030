// Tests of the scenario generators: recipes, determinism, physical sanity and label balance.
#include "engine/sim/scenario.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "engine/core/error.h"
#include "engine/sim/scene_checks.h"

namespace dynscope {
namespace {

const std::vector<std::string> kPhysionLike = {"drop",    "collide", "roll", "dominoes",
                                               "support", "contain", "link"};

bool same_scene(const Scene& a, const Scene& b) {
  if (a.objects.size() != b.objects.size() || a.num_frames() != b.num_frames()) return false;
  for (size_t i = 0; i < a.objects.size(); ++i) {
    const Object &x = a.objects[i], &y = b.objects[i];
    if (x.name != y.name || x.mass != y.mass || x.scale != y.scale ||
        x.mesh.vertices != y.mesh.vertices || x.mesh.faces != y.mesh.faces) {
      return false;
    }
    for (int f = 0; f < a.num_frames(); ++f) {
      const Pose &p = a.trajectories[i].poses[f], &q = b.trajectories[i].poses[f];
      if (p.position != q.position || p.rotation.coeffs() != q.rotation.coeffs()) return false;
    }
  }
  return a.labels == b.labels && a.dt_s == b.dt_s && a.seed == b.seed;
}

TEST(Scenarios, ListsEveryScenario) {
  const std::vector<std::string> names = scenario_names();
  for (const std::string& n : kPhysionLike) {
    EXPECT_TRUE(is_scenario(n)) << n;
    EXPECT_TRUE(scenario_has_contact_label(n)) << n;
  }
  EXPECT_TRUE(is_scenario("movi-a"));
  EXPECT_FALSE(scenario_has_contact_label("movi-a"));
  EXPECT_EQ(names.size(), kPhysionLike.size() + 2);
  EXPECT_FALSE(scenario_summary("roll").empty());
  EXPECT_NE(scenario_parameters_json("dominoes").find("\"num_frames\""), std::string::npos);
}

TEST(Scenarios, UnknownNameListsTheKnownOnes) {
  try {
    generate_scene("bogus", 1);
    FAIL() << "unknown scenario accepted";
  } catch (const ValueError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bogus"), std::string::npos) << what;
    EXPECT_NE(what.find("movi-a"), std::string::npos) << what;
    EXPECT_NE(what.find("dominoes"), std::string::npos) << what;
  }
  EXPECT_THROW(scenario_parameters_json("bogus"), ValueError);
  EXPECT_THROW(generate_scene("movi-c", 1), ValueError) << "movi-c needs meshes";
}

TEST(Scenarios, SameSeedSameSceneOtherSeedOtherScene) {
  for (const std::string& name : scenario_names()) {
    if (scenario_needs_meshes(name)) continue;
    const Scene a = generate_scene(name, 42), b = generate_scene(name, 42);
    const Scene c = generate_scene(name, 43);
    EXPECT_TRUE(same_scene(a, b)) << name;
    EXPECT_FALSE(same_scene(a, c)) << name;
    EXPECT_EQ(a.scenario, name);
    EXPECT_EQ(a.seed, 42u);
  }
}

// Another frame rate stores the same simulation more or less densely over the same time.
TEST(Scenarios, FrameRateStoresTheSameSimulationMoreDensely) {
  for (const std::string& name : {std::string("collide"), std::string("link")}) {
    const Scene own = generate_scene(name, 7);
    ScenarioOptions options;
    options.frame_rate_hz = 60.0;
    const Scene dense = generate_scene(name, 7, options);
    ASSERT_EQ(dense.num_frames(), 2 * (own.num_frames() - 1) + 1) << name;
    EXPECT_DOUBLE_EQ(dense.dt_s, own.dt_s / 2) << name;
    ASSERT_EQ(dense.objects.size(), own.objects.size());
    for (size_t i = 0; i < own.objects.size(); ++i) {
      for (int f = 0; f < own.num_frames(); ++f) {
        const Pose &p = own.trajectories[i].poses[f], &q = dense.trajectories[i].poses[2 * f];
        ASSERT_EQ(p.position, q.position) << name << " object " << i << " frame " << f;
        ASSERT_EQ(p.rotation.coeffs(), q.rotation.coeffs()) << name << " frame " << f;
      }
    }
    // The label covers every physics step either way, so the outcome is the same.
    EXPECT_EQ(contact_outcome(dense), contact_outcome(own)) << name;
    const std::vector<double>& sparse = own.labels.at(kContactLabel);
    const std::vector<double>& fine = dense.labels.at(kContactLabel);
    for (int f = 1; f < own.num_frames(); ++f) {
      EXPECT_EQ(sparse[f], std::max(fine[2 * f - 1], fine[2 * f])) << name << " frame " << f;
    }
  }
  // 120 Hz: two physics steps per frame over collide's 472 (59 frames after the first of 30 Hz).
  ScenarioOptions fast;
  fast.frame_rate_hz = 120.0;
  EXPECT_EQ(scenario_setup("collide", 7, fast).num_frames, 237);
  EXPECT_EQ(scenario_setup("collide", 7, fast).substeps_per_frame, 2);
}

// A lower rate whose interval does not divide the run: every third frame of the 30 Hz twin at 10 Hz,
// and the simulation runs on to the next whole frame (collide's 472 physics steps are 19 intervals
// of 24 and 16 steps, so a 20th interval ends 8 steps after the twin's last frame).
TEST(Scenarios, FrameRateBelowTheRunsDivisorsRunsOnToTheNextWholeFrame) {
  for (const std::string& name : {std::string("collide"), std::string("roll")}) {
    const Scene own = generate_scene(name, 7);
    ScenarioOptions options;
    options.frame_rate_hz = 10.0;
    const Scene slow = generate_scene(name, 7, options);
    const int whole = (own.num_frames() - 1) / 3;  // the twin's frames that fall on this rate's
    ASSERT_EQ(slow.num_frames(), whole + 2) << name;
    EXPECT_DOUBLE_EQ(slow.dt_s, 3 * own.dt_s) << name;
    ASSERT_EQ(slow.objects.size(), own.objects.size());
    for (size_t i = 0; i < own.objects.size(); ++i) {
      for (int f = 0; f <= whole; ++f) {
        const Pose &p = own.trajectories[i].poses[3 * f], &q = slow.trajectories[i].poses[f];
        ASSERT_EQ(p.position, q.position) << name << " object " << i << " frame " << f;
        ASSERT_EQ(p.rotation.coeffs(), q.rotation.coeffs()) << name << " frame " << f;
      }
    }
    const std::vector<double>& twin = own.labels.at(kContactLabel);
    const std::vector<double>& coarse = slow.labels.at(kContactLabel);
    EXPECT_EQ(coarse[0], twin[0]) << name;
    for (int f = 1; f <= whole; ++f) {
      EXPECT_EQ(coarse[f], std::max({twin[3 * f - 2], twin[3 * f - 1], twin[3 * f]}))
          << name << " frame " << f;
    }
    // The last interval covers the twin's remaining frames and runs on past them.
    double rest = 0;
    for (int f = 3 * whole + 1; f < own.num_frames(); ++f) rest = std::max(rest, twin[f]);
    EXPECT_GE(coarse[whole + 1], rest) << name;
    EXPECT_GE(contact_outcome(slow), contact_outcome(own)) << name;
  }
  ScenarioOptions fifteen;
  fifteen.frame_rate_hz = 15.0;  // 16 steps: 472 = 29 × 16 + 8
  EXPECT_EQ(scenario_setup("collide", 7, fifteen).num_frames, 31);
  EXPECT_EQ(scenario_setup("collide", 7, fifteen).substeps_per_frame, 16);
}

// Sparse meshes change what is stored, not what is simulated: the same poses frame by frame, and
// boxes and cylinders keep only the vertices their shapes need. Movi-c's user meshes stay as given.
TEST(Scenarios, SparseMeshesStoreTheSameSimulation) {
  for (const std::string& name : {std::string("movi-a"), std::string("support")}) {
    const Scene dense = generate_scene(name, 11);
    ScenarioOptions options;
    options.mesh_density = MeshDensity::kSparse;
    const Scene sparse = generate_scene(name, 11, options);
    ASSERT_EQ(sparse.objects.size(), dense.objects.size()) << name;
    ASSERT_EQ(sparse.num_frames(), dense.num_frames()) << name;
    int fewer = 0;
    for (size_t i = 0; i < dense.objects.size(); ++i) {
      EXPECT_EQ(sparse.objects[i].mass, dense.objects[i].mass) << name << " object " << i;
      EXPECT_LE(sparse.objects[i].mesh.num_vertices(), dense.objects[i].mesh.num_vertices());
      fewer += sparse.objects[i].mesh.num_vertices() < dense.objects[i].mesh.num_vertices();
      for (int f = 0; f < dense.num_frames(); ++f) {
        const Pose &p = dense.trajectories[i].poses[f], &q = sparse.trajectories[i].poses[f];
        ASSERT_EQ(p.position, q.position) << name << " object " << i << " frame " << f;
        ASSERT_EQ(p.rotation.coeffs(), q.rotation.coeffs()) << name << " frame " << f;
      }
    }
    EXPECT_GT(fewer, 0) << name << ": no box or cylinder got sparser";
  }
  ScenarioOptions options;
  options.mesh_density = MeshDensity::kSparse;
  options.meshes = {make_sphere_mesh(1.0, 6, 8)};
  try {
    scenario_setup("movi-c", 3, options);
    ADD_FAILURE() << "sparse movi-c was accepted";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("mesh_density"), std::string::npos) << e.what();
  }
}

// A frame must fall on a physics step: 70 Hz would be 3.43 of the 240 Hz steps per frame.
TEST(Scenarios, FrameRateThatDoesNotFitNamesTheRatesThatDo) {
  ScenarioOptions options;
  for (const double bad : {70.0, 45.0, 7.0, 480.0, -30.0}) {
    options.frame_rate_hz = bad;
    try {
      scenario_setup("collide", 7, options);
      ADD_FAILURE() << bad << " Hz was accepted";
    } catch (const ValueError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("frame_rate"), std::string::npos) << message;
      EXPECT_NE(message.find("rates that fit: 240, 120, 80, 60, 48, 40, 30, 24, 20, 16, 15, 12, 10, "
                             "8, 6, 5, 4, 3, 2, 1)"),
                std::string::npos)
          << message;
    }
  }
}

TEST(Scenarios, ScenesAreValidAndStartWithoutInterpenetration) {
  for (const std::string& name : scenario_names()) {
    if (scenario_needs_meshes(name)) continue;
    for (uint64_t seed = 0; seed < 5; ++seed) {
      const Scene scene = generate_scene(name, seed);
      EXPECT_NO_THROW(scene.validate()) << name << " seed " << seed;
      // Stored meshes match the collision shapes up to Bullet's edge rounding (< 0.4 % of a
      // part's half size): under 1 mm at Physion scale, 5 mm for MOVi-A's 0.7-1.4 objects.
      const double tolerance = name == "movi-a" ? 5e-3 : 1e-3;
      EXPECT_LT(max_penetration(scene, 0), tolerance) << name << " seed " << seed;
    }
  }
}

TEST(Scenarios, PhysionLikeScenesHaveOneRedTargetAndOneYellowZone) {
  for (const std::string& name : kPhysionLike) {
    for (uint64_t seed = 0; seed < 5; ++seed) {
      const Scene scene = generate_scene(name, seed);
      int targets = 0, zones = 0;
      for (const Object& o : scene.objects) {
        targets += o.role == Role::kTarget;
        zones += o.role == Role::kZone;
        if (o.role == Role::kTarget) {
          EXPECT_GT(o.color.x(), 0.5 + o.color.y() + o.color.z());
        }
        if (o.role == Role::kZone) {
          EXPECT_GT(std::min(o.color.x(), o.color.y()), 3 * o.color.z()) << "yellow";
          EXPECT_EQ(o.mass, 0.0) << "static pad";
        }
        // Physion scale: every movable object is 5-50 cm across.
        if (o.mass > 0) {
          const Aabb box = Aabb::of(o.scaled_mesh().vertices);
          EXPECT_GE((box.max - box.min).maxCoeff(), 0.05) << name << " " << o.name;
          EXPECT_LE((box.max - box.min).maxCoeff(), 0.5) << name << " " << o.name;
        }
      }
      EXPECT_EQ(targets, 1) << name;
      EXPECT_EQ(zones, 1) << name;
      const std::vector<double>& label = scene.labels.at(kContactLabel);
      ASSERT_EQ(label.size(), static_cast<size_t>(scene.num_frames()));
      EXPECT_EQ(label.front(), 0.0) << name << " seed " << seed << ": touching at frame 0";
    }
  }
}

TEST(MoviA, RecipeStatisticsOver50Scenes) {
  std::set<int> counts;
  std::set<std::string> shapes;
  for (uint64_t seed = 0; seed < 50; ++seed) {
    const SimSetup setup = scenario_setup("movi-a", seed);
    EXPECT_EQ(setup.num_frames, 24);
    EXPECT_DOUBLE_EQ(setup.frame_dt_s(), 1.0 / 12.0);
    EXPECT_DOUBLE_EQ(setup.physics_rate_hz, 240.0);
    EXPECT_DOUBLE_EQ(setup.gravity, 10.0);
    const int n = static_cast<int>(setup.bodies.size());
    EXPECT_GE(n, 3);
    EXPECT_LE(n, 10);
    counts.insert(n);
    for (const BodySpec& b : setup.bodies) {
      const double s = b.object.scale.x();
      EXPECT_TRUE(s == 0.7 || s == 1.4) << s;
      EXPECT_EQ(b.object.scale, Vec3::Constant(s));
      shapes.insert(b.object.name.substr(0, b.object.name.find('_')));
      const bool rubber = b.object.friction == 0.8 && b.object.restitution == 0.7;
      const bool metal = b.object.friction == 0.4 && b.object.restitution == 0.3;
      EXPECT_TRUE(rubber || metal);
      EXPECT_NEAR(b.object.mass, (rubber ? 1.1 : 2.7) * body_volume(b.parts, b.object.scale), 1e-9);
      const Vec3 p = b.pose.position;
      const Vec3 random_part = b.linear_velocity + Vec3(p.x(), p.y(), 0);
      EXPECT_LE(random_part.head<2>().cwiseAbs().maxCoeff(), 4.0);
      EXPECT_EQ(b.linear_velocity.z(), 0.0);
      EXPECT_EQ(b.angular_velocity, Vec3::Zero());
      // Kubric's placement: bounds inside [(-5,-5,1),(5,5,5)] along every axis where they fit;
      // a taller object is centred within the region shrunk by its bounds (reversed interval).
      const Aabb box = body_aabb(b.parts, b.object.scale, b.pose);
      const Vec3 lo(-5, -5, 1), hi(5, 5, 5);
      for (int a = 0; a < 3; ++a) {
        if (box.max[a] - box.min[a] <= hi[a] - lo[a]) {
          EXPECT_GE(box.min[a], lo[a] - 1e-9) << "axis " << a;
          EXPECT_LE(box.max[a], hi[a] + 1e-9) << "axis " << a;
        } else {
          EXPECT_LE(box.min[a], lo[a] + 1e-9) << "axis " << a;
          EXPECT_GE(box.max[a], hi[a] - 1e-9) << "axis " << a;
        }
      }
      EXPECT_GT(box.min.z(), 0.0) << "spawned above the floor";
    }
  }
  EXPECT_GE(counts.size(), 5u) << "object counts vary over 3-10";
  EXPECT_EQ(shapes, (std::set<std::string>{"cube", "cylinder", "sphere"}));
}

TEST(MoviA, MeshIsTheUnitShapeScaled) {
  const Scene scene = generate_scene("movi-a", 7);
  for (const Object& o : scene.objects) {
    const Aabb box = Aabb::of(o.mesh.vertices);
    EXPECT_NEAR(box.max.maxCoeff(), 1.0, 1e-12) << o.name << ": unit shapes span [-1, 1]";
    EXPECT_NEAR(box.min.minCoeff(), -1.0, 1e-12) << o.name;
  }
}

TEST(MoviA, NoObjectBelowTheFloorAfterTheLastFrame) {
  for (uint64_t seed = 0; seed < 10; ++seed) {
    const Scene scene = generate_scene("movi-a", seed);
    const int last = scene.num_frames() - 1;
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      const double lowest = scene.world_vertices(static_cast<int>(i), last).col(2).minCoeff();
      EXPECT_GT(lowest, -0.02) << "seed " << seed << " " << scene.objects[i].name;
    }
  }
}

TEST(MoviC, UserMeshesBecomeConvexHullBodies) {
  ScenarioOptions options;
  // A tetrahedron-like spike 2 x 1 x 1 in arbitrary units, off the origin.
  Mesh m;
  m.vertices.resize(4, 3);
  m.vertices << 10, 0, 0, 12, 0, 0, 10, 1, 0, 10, 0, 1;
  m.faces.resize(4, 3);
  m.faces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  options.meshes.push_back(m);
  const Scene scene = generate_scene("movi-c", 3, options);
  EXPECT_EQ(scene.scenario, "movi-c");
  ASSERT_GE(scene.objects.size(), 3u);
  for (const Object& o : scene.objects) {
    const Aabb box = Aabb::of(o.mesh.vertices);
    EXPECT_NEAR((box.max - box.min).maxCoeff(), 2.0, 1e-12) << "normalised to span [-1, 1]";
    EXPECT_GE(2 * o.scale.x(), 0.75);
    EXPECT_LE(2 * o.scale.x(), 3.0);
  }
  EXPECT_LT(max_penetration(scene, 0), 1e-3);
}

TEST(DropScenario, TargetFallsWithGBeforeImpact) {
  for (uint64_t seed = 0; seed < 5; ++seed) {
    const Scene scene = generate_scene("drop", seed);
    const int t = scene.find_role(Role::kTarget);
    const double z0 = scene.trajectories[t].poses[0].position.z();
    const double h = 1.0 / 240.0;
    // The target starts at least 0.4 m up and obstacles are at most 0.28 m tall, so it falls
    // freely for more than 4 frames (0.133 s, 8.7 cm).
    for (int f = 1; f <= 4; ++f) {
      const double time = f * scene.dt_s;
      EXPECT_NEAR(scene.trajectories[t].poses[f].position.z(), z0 - 0.5 * 9.81 * time * time,
                  9.81 * time * h)
          << "seed " << seed << " frame " << f;
    }
  }
}

TEST(PhysionLike, BothOutcomesOccurIn20Trials) {
  for (const std::string& name : kPhysionLike) {
    int positives = 0;
    for (uint64_t seed = 0; seed < 20; ++seed)
      positives += contact_outcome(generate_scene(name, seed));
    EXPECT_GT(positives, 0) << name;
    EXPECT_LT(positives, 20) << name;
  }
}

}  // namespace
}  // namespace dynscope
