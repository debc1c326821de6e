// The GLES runtime on Mesa (llvmpipe) through an EGL surfaceless context: equality with the CPU
// reference, budgets, whole changes, latency, fixed memory, drift and context loss.
#include "lightpatch/runtime.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "counters.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/platform/egl_context.h"
#include "lightpatch/platform/gl.h"
#include "lightpatch/scene_state.h"
#include "runtime/map_reference.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch {
namespace {

using testing::make_synthetic_pack;
using testing::reference_map;
using testing::RefState;
using testing::SyntheticOptions;

constexpr uint64_t kUnlimited = ~0ull >> 1;
constexpr double kHalfUlp = 1.0 / 2048.0;

class Gles : public ::testing::Test {
 protected:
  void SetUp() override {
    char message[256] = {};
    ASSERT_TRUE(context_.create_headless(message, sizeof message)) << message;
  }
  void open(const SyntheticOptions& o, bool cpu = false) {
    bytes_ = make_synthetic_pack(o);
    Error error;
    ASSERT_TRUE(bytes_.open(&pack_, &error)) << error.message;
    RuntimeLimits limits;
    limits.force_cpu_fallback = cpu;
    ASSERT_EQ(runtime_.open(pack_, limits, &error), Status::kOk) << error.message;
    ASSERT_EQ(runtime_.gpu_path(), !cpu);
  }
  int settle(uint64_t budget, int max_frames = 100000) {
    int frames = 0;
    while (!runtime_.idle() && frames < max_frames) {
      EXPECT_EQ(runtime_.update(budget), Status::kOk);
      ++frames;
    }
    return frames;
  }
  // The sampled map as RGB (drops alpha).
  std::vector<float> read() {
    std::vector<float> rgba(size_t(runtime_.width()) * runtime_.height() * 4);
    Error error;
    EXPECT_EQ(runtime_.read_light_map(rgba.data(), &error), Status::kOk) << error.message;
    std::vector<float> rgb(rgba.size() / 4 * 3);
    for (size_t i = 0; i < rgba.size() / 4; ++i) {
      for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = rgba[i * 4 + c];
    }
    return rgb;
  }
  void random_change(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    if (pack_.object_count() > 0 && u(rng) < 0.4f) {
      const uint32_t o = rng() % pack_.object_count();
      ASSERT_EQ(runtime_.set_object_visible(o, !runtime_.object_visible(o)), Status::kOk);
    } else {
      const uint32_t l = rng() % pack_.light_count();
      LightState s{u(rng) < 0.8f, {u(rng), u(rng), u(rng)}, 4.0f * u(rng)};
      ASSERT_EQ(runtime_.set_light(l, s), Status::kOk);
    }
  }
  // Max over texels of |got - want| / tolerance, tolerance = `ulps` half-float rounding of the
  // texel's sum of absolute terms (+ a tiny absolute floor).
  double error_in_ulps(const std::vector<float>& got, const std::vector<double>& want,
                       const std::vector<double>& magnitude, double extra = 0.0) {
    double worst = 0.0;
    for (size_t i = 0; i < got.size(); ++i) {
      const double tol = kHalfUlp * magnitude[i] + extra + 1e-7;
      worst = std::max(worst, std::fabs(double(got[i]) - want[i]) / tol);
    }
    return worst;
  }

  platform::EglContext context_;
  testing::SyntheticPack bytes_;
  PackView pack_;
  Runtime runtime_;
};

TEST_F(Gles, RecomposeEqualsCpuReferenceForRandomStates) {
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    SyntheticOptions o;
    o.seed = seed;
    o.lights = 2 + seed % 3;
    o.objects = 1 + seed % 4;
    if (seed == 4) {  // many atlases: groups span more than 8 texture units
      o.atlas_size = 8;
      o.max_patch = 6;
      o.patches_per_group = 12;
    }
    open(o);
    if (seed == 4) {
      ASSERT_GT(pack_.atlas_count(), 8u);
    }
    Error error;
    SceneState state;
    ASSERT_EQ(state.init(pack_, &error), Status::kOk);
    CpuRecomposer cpu;
    ASSERT_EQ(cpu.init(pack_, &error), Status::kOk);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int trial = 0; trial < 4; ++trial) {
      for (uint32_t l = 0; l < pack_.light_count(); ++l) {
        LightState s{u(rng) < 0.7f, {u(rng), u(rng), u(rng)}, 3.0f * u(rng)};
        ASSERT_EQ(state.set_light(l, s), Status::kOk);
        ASSERT_EQ(runtime_.set_light(l, s), Status::kOk);
      }
      for (uint32_t ob = 0; ob < pack_.object_count(); ++ob) {
        const bool v = u(rng) < 0.5f;
        ASSERT_EQ(state.set_object_visible(ob, v), Status::kOk);
        ASSERT_EQ(runtime_.set_object_visible(ob, v), Status::kOk);
      }
      settle(kUnlimited);
      ASSERT_EQ(cpu.rebuild(state), Status::kOk);
      const std::vector<float> got = read();
      RefState ref_state = testing::wanted_state(runtime_.planner(), pack_);
      std::vector<double> magnitude;
      reference_map(pack_, ref_state, &magnitude);
      std::vector<double> want(cpu.rgb(), cpu.rgb() + got.size());
      // Incremental history since the last rebuild adds at most the runtime's error bound.
      const double ulps = error_in_ulps(got, want, magnitude, runtime_.stats().error_bound);
      EXPECT_LE(ulps, 8.0) << "seed " << seed << " trial " << trial;
    }
    runtime_.close();
  }
}

TEST_F(Gles, BudgetNeverExceededAndNoPartialStateSampled) {
  SyntheticOptions o;
  o.seed = 11;
  open(o);
  std::mt19937 rng(5);
  const uint64_t budgets[] = {60, 250, 900, 4000};
  uint32_t presents = 0;
  for (int frame = 0; frame < 150; ++frame) {
    if (rng() % 3 == 0) random_change(rng);
    const uint64_t budget = budgets[rng() % 4];
    ASSERT_EQ(runtime_.update(budget), Status::kOk);
    const FrameStats& s = runtime_.stats();
    presents += s.presented;
    if (!s.oversize_steps) {
      ASSERT_LE(s.texels, budget);
    } else {
      ASSERT_LE(s.draws, 1u);
    }
    if (!runtime_.ready()) continue;
    // What the game samples is exactly the presented state: never half a change or a rebuild.
    std::vector<double> magnitude;
    const auto want =
        reference_map(pack_, testing::shown_state(runtime_.planner(), pack_), &magnitude);
    ASSERT_LE(error_in_ulps(read(), want, magnitude, s.error_bound), 8.0) << "frame " << frame;
  }
  EXPECT_GT(presents, 1u);
}

TEST_F(Gles, ChangesDuringARebuildAreNotLostAndLatencyIsBounded) {
  SyntheticOptions o;
  o.seed = 12;
  open(o);
  const uint64_t budget = 300;
  std::mt19937 rng(8);
  uint32_t worst = 0;
  for (int frame = 0; frame < 40; ++frame) {
    if (frame < 15) random_change(rng);
    ASSERT_EQ(runtime_.update(budget), Status::kOk);
    worst = std::max(worst, runtime_.stats().max_latency_frames);
    worst = std::max(worst, runtime_.stats().oldest_pending_frames);
  }
  settle(budget);
  const uint64_t rebuild = runtime_.planner().rebuild_texels();
  EXPECT_LE(worst, uint32_t(2 * ((rebuild + budget - 1) / budget) + 3));
  std::vector<double> magnitude;
  const auto want =
      reference_map(pack_, testing::wanted_state(runtime_.planner(), pack_), &magnitude);
  EXPECT_LE(error_in_ulps(read(), want, magnitude, runtime_.stats().error_bound), 8.0);
}

TEST_F(Gles, NoAllocationAndNoGlObjectCreationPerFrame) {
  SyntheticOptions o;
  o.seed = 13;
  open(o);
  settle(kUnlimited);
  std::mt19937 rng(21);
  // Pre-draw the random changes so the test's own bookkeeping allocates nothing while counting.
  std::vector<uint32_t> picks(3000);
  for (uint32_t& p : picks) p = rng();
  // Warm the driver's state variants (shader variants, first use of each target).
  for (int i = 0; i < 50; ++i) {
    random_change(rng);
    ASSERT_EQ(runtime_.update(500), Status::kOk);
  }
  testing::Counters& c = testing::counters();
  // Positive control: opening a runtime is where memory and GL objects are made, and the
  // counters see it.
  {
    c.news = c.mallocs = c.gl_creations = 0;
    c.on = true;
    Runtime other;
    Error error;
    ASSERT_EQ(other.open(pack_, RuntimeLimits(), &error), Status::kOk);
    c.on = false;
    EXPECT_GE(c.gl_creations, 5u);  // atlases, maps, framebuffers, buffers, VAO, shaders, program
    if (testing::malloc_counted()) {
      EXPECT_GT(c.mallocs, 0u);
    }
  }
  c.news = c.mallocs = c.gl_creations = 0;
  c.on = true;
  uint64_t frames_with_alloc = 0;
  for (size_t i = 0; i + 2 < picks.size(); i += 3) {
    const uint64_t before = c.news + c.mallocs;
    if (pack_.object_count() && picks[i] % 5 < 2) {
      const uint32_t ob = picks[i + 1] % pack_.object_count();
      runtime_.set_object_visible(ob, !runtime_.object_visible(ob));
    } else {
      LightState s{picks[i + 1] % 4 != 0,
                   {float(picks[i + 2] % 7) / 7.0f, 0.5f, 0.25f},
                   float(picks[i + 1] % 5)};
      runtime_.set_light(picks[i] % pack_.light_count(), s);
    }
    const uint64_t budgets[] = {100, 700, 3000};
    runtime_.update(budgets[picks[i + 2] % 3]);
    frames_with_alloc += (c.news + c.mallocs) != before;
  }
  c.on = false;
  EXPECT_EQ(c.gl_creations, 0u);
  EXPECT_EQ(c.news, 0u);
  if (testing::malloc_counted()) {
    // malloc/calloc/realloc called from the runtime's code (not from inside the GL driver).
    EXPECT_EQ(c.mallocs, 0u) << frames_with_alloc << " frames allocated";
  }
}

TEST_F(Gles, NoDriftAfterTenThousandRandomChanges) {
  SyntheticOptions o;
  o.seed = 14;
  o.width = 32;
  o.height = 24;
  o.max_patch = 8;
  open(o);
  settle(kUnlimited);
  std::mt19937 rng(1234);
  for (int i = 0; i < 10000; ++i) {
    random_change(rng);
    ASSERT_EQ(runtime_.update(kUnlimited), Status::kOk);
  }
  settle(kUnlimited);
  const std::vector<float> incremental = read();
  const double bound = runtime_.stats().error_bound;
  std::vector<double> magnitude;
  const auto exact =
      reference_map(pack_, testing::wanted_state(runtime_.planner(), pack_), &magnitude);
  EXPECT_LE(error_in_ulps(incremental, exact, magnitude, bound), 8.0);
  // And against a fresh rebuild on the GPU of the same state.
  runtime_.request_rebuild();
  settle(kUnlimited);
  const std::vector<float> fresh = read();
  for (size_t i = 0; i < fresh.size(); ++i) {
    ASSERT_LE(std::fabs(double(fresh[i]) - incremental[i]),
              bound + 16 * kHalfUlp * magnitude[i] + 1e-6);
  }
}

TEST_F(Gles, SurvivesContextLoss) {
  SyntheticOptions o;
  o.seed = 15;
  open(o);
  std::mt19937 rng(3);
  for (int i = 0; i < 5; ++i) random_change(rng);
  settle(kUnlimited);
  runtime_.request_rebuild();
  settle(kUnlimited);
  const std::vector<float> before = read();
  context_.destroy();
  char message[256] = {};
  ASSERT_TRUE(context_.create_headless(message, sizeof message)) << message;
  Error error;
  ASSERT_EQ(runtime_.restore(&error), Status::kOk) << error.message;
  EXPECT_FALSE(runtime_.ready());
  settle(500);
  EXPECT_EQ(read(), before);
}

TEST_F(Gles, CpuFallbackMatchesTheGpuPath) {
  SyntheticOptions o;
  o.seed = 16;
  open(o, /*cpu=*/true);
  std::mt19937 rng(4);
  for (int i = 0; i < 6; ++i) random_change(rng);
  settle(400);
  std::vector<double> magnitude;
  const auto want =
      reference_map(pack_, testing::wanted_state(runtime_.planner(), pack_), &magnitude);
  // The CPU path accumulates in float and uploads to RGBA16F: one half rounding at most.
  std::vector<float> got(size_t(runtime_.width()) * runtime_.height() * 4);
  GLuint fbo = 0;
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                         runtime_.light_map_texture(), 0);
  ASSERT_EQ(glCheckFramebufferStatus(GL_FRAMEBUFFER), GLenum(GL_FRAMEBUFFER_COMPLETE));
  glReadPixels(0, 0, GLsizei(runtime_.width()), GLsizei(runtime_.height()), GL_RGBA, GL_FLOAT,
               got.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(1, &fbo);
  std::vector<float> rgb(got.size() / 4 * 3);
  for (size_t i = 0; i < got.size() / 4; ++i) {
    for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = got[i * 4 + c];
  }
  EXPECT_LE(error_in_ulps(rgb, want, magnitude, runtime_.stats().error_bound), 2.0);
}

TEST_F(Gles, RowZeroIsTheTopRow) {
  // One base patch in the top-left corner only: the first row read back must carry it.
  SyntheticOptions o;
  o.seed = 17;
  open(o);
  settle(kUnlimited);
  const std::vector<float> got = read();
  std::vector<double> magnitude;
  const auto want =
      reference_map(pack_, testing::wanted_state(runtime_.planner(), pack_), &magnitude);
  // The map is asymmetric: a vertical flip would not match.
  EXPECT_LE(error_in_ulps(got, want, magnitude), 8.0);
  std::vector<double> flipped(want.size());
  const uint32_t w = runtime_.width(), h = runtime_.height();
  for (uint32_t y = 0; y < h; ++y) {
    for (size_t i = 0; i < size_t(w) * 3; ++i)
      flipped[size_t(y) * w * 3 + i] = want[size_t(h - 1 - y) * w * 3 + i];
  }
  EXPECT_GT(error_in_ulps(got, flipped, magnitude), 8.0);
}

TEST_F(Gles, QueriesByNameAndRejectsBadValues) {
  open(SyntheticOptions{});
  EXPECT_EQ(runtime_.find_light("light_1"), 1);
  EXPECT_EQ(runtime_.find_object("object_2"), 2);
  EXPECT_EQ(runtime_.find_light("nope"), -1);
  EXPECT_EQ(runtime_.set_light_intensity(0, -1.0f), Status::kInvalidArgument);
  EXPECT_EQ(runtime_.set_light_on(99, true), Status::kInvalidArgument);
  const RuntimeMemory m = runtime_.memory();
  EXPECT_EQ(m.light_map, uint64_t(runtime_.width()) * runtime_.height() * 8);
  EXPECT_EQ(m.intermediate, m.light_map);
  EXPECT_EQ(m.atlases, uint64_t(pack_.atlas_count()) * 64 * 64 * 4);
}

}  // namespace
}  // namespace lightpatch
