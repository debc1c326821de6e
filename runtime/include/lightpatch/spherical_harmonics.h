// Order-2 real spherical harmonics (9 coefficients per channel) for the light probes
// (pack_format.h, "Light probes"): one definition of the basis and of the cosine-lobe
// convolution, shared by the cooker that projects and the runtime that evaluates.
#pragma once

#include <cstdint>

#include "lightpatch/pack_format.h"

namespace lightpatch {

// Y_k(n) for k = 0..8 in the pack's order (Y00, Y1-1, Y10, Y11, Y2-2, Y2-1, Y20, Y21, Y22) of the
// unit direction n = (x, y, z).
inline void sh_basis(float x, float y, float z, float out[pack::kProbeShCount]) {
  out[0] = 0.282095f;
  out[1] = 0.488603f * y;
  out[2] = 0.488603f * z;
  out[3] = 0.488603f * x;
  out[4] = 1.092548f * x * y;
  out[5] = 1.092548f * y * z;
  out[6] = 0.315392f * (3.0f * z * z - 1.0f);
  out[7] = 1.092548f * x * z;
  out[8] = 0.546274f * (x * x - y * y);
}

// The clamped cosine lobe's convolution per band (Ramamoorthi & Hanrahan 2001): radiance SH
// coefficients times these are irradiance SH coefficients (pi, 2 pi / 3, pi / 4).
constexpr float kShCosineBand[3] = {3.14159265f, 2.09439510f, 0.78539816f};
constexpr int sh_band(uint32_t k) { return k == 0 ? 0 : (k < 4 ? 1 : 2); }

// E(n) per channel from irradiance coefficients sh[k * 3 + c], not clamped (a game lights with
// max(E, 0)).
inline void sh_irradiance(const float sh[pack::kProbeShCount * 3], float x, float y, float z,
                          float out_rgb[3]) {
  float y_k[pack::kProbeShCount];
  sh_basis(x, y, z, y_k);
  for (int c = 0; c < 3; ++c) {
    float e = 0.0f;
    for (uint32_t k = 0; k < pack::kProbeShCount; ++k) e += sh[k * 3 + c] * y_k[k];
    out_rgb[c] = e;
  }
}

}  // namespace lightpatch
