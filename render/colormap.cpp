// Colormap tables: anchors from matplotlib's viridis and Google's turbo, linearly interpolated.
#include "render/colormap.h"

#include <algorithm>
#include <cmath>

#include "engine/core/error.h"

namespace dynscope::render {
namespace {

struct Anchor {
  float t, r, g, b;
};

// matplotlib viridis at t = 0, 0.1, ..., 1.
constexpr Anchor kViridis[] = {
    {0.0f, 0.267004f, 0.004874f, 0.329415f}, {0.1f, 0.282623f, 0.140926f, 0.457517f},
    {0.2f, 0.253935f, 0.265254f, 0.529983f}, {0.3f, 0.206756f, 0.371758f, 0.553117f},
    {0.4f, 0.163625f, 0.471133f, 0.558148f}, {0.5f, 0.127568f, 0.566949f, 0.550556f},
    {0.6f, 0.134692f, 0.658636f, 0.517649f}, {0.7f, 0.266941f, 0.748751f, 0.440573f},
    {0.8f, 0.477504f, 0.821444f, 0.318195f}, {0.9f, 0.741388f, 0.873449f, 0.149561f},
    {1.0f, 0.993248f, 0.906157f, 0.143936f},
};

// Turbo (Mikhailov 2019) lookup table entries 0, 16, ..., 240, 255 at t = index / 255.
constexpr Anchor kTurbo[] = {
    {0.0f / 255, 0.18995f, 0.07176f, 0.23217f},   {16.0f / 255, 0.25107f, 0.25237f, 0.63374f},
    {32.0f / 255, 0.27628f, 0.42118f, 0.89123f},  {48.0f / 255, 0.25862f, 0.57958f, 0.99876f},
    {64.0f / 255, 0.15844f, 0.73551f, 0.92305f},  {80.0f / 255, 0.09267f, 0.86554f, 0.76230f},
    {96.0f / 255, 0.19659f, 0.94901f, 0.59466f},  {112.0f / 255, 0.42778f, 0.99419f, 0.38575f},
    {128.0f / 255, 0.64362f, 0.98999f, 0.23356f}, {144.0f / 255, 0.80473f, 0.92452f, 0.20459f},
    {160.0f / 255, 0.93301f, 0.81236f, 0.22667f}, {176.0f / 255, 0.99314f, 0.67408f, 0.20348f},
    {192.0f / 255, 0.98360f, 0.49291f, 0.12849f}, {208.0f / 255, 0.92105f, 0.31489f, 0.05475f},
    {224.0f / 255, 0.81608f, 0.18462f, 0.01809f}, {240.0f / 255, 0.66449f, 0.08436f, 0.00424f},
    {255.0f / 255, 0.47960f, 0.01583f, 0.01055f},
};

// Tableau 10 (matplotlib "tab10").
constexpr float kTab10[10][3] = {
    {0.122f, 0.467f, 0.706f}, {1.000f, 0.498f, 0.055f}, {0.173f, 0.627f, 0.173f},
    {0.839f, 0.153f, 0.157f}, {0.580f, 0.404f, 0.741f}, {0.549f, 0.337f, 0.294f},
    {0.890f, 0.467f, 0.761f}, {0.498f, 0.498f, 0.498f}, {0.737f, 0.741f, 0.133f},
    {0.090f, 0.745f, 0.812f},
};

template <size_t N>
Color interpolate(const Anchor (&anchors)[N], float t) {
  t = std::clamp(std::isfinite(t) ? t : 0.0f, 0.0f, 1.0f);
  size_t i = 1;
  while (i < N - 1 && anchors[i].t < t) ++i;
  const Anchor& a = anchors[i - 1];
  const Anchor& b = anchors[i];
  const float s = (t - a.t) / (b.t - a.t);
  return Color(a.r + s * (b.r - a.r), a.g + s * (b.g - a.g), a.b + s * (b.b - a.b));
}

}  // namespace

const std::vector<std::string>& colormap_names() {
  static const std::vector<std::string> kNames = {"viridis", "turbo"};
  return kNames;
}

void check_colormap(const std::string& name) {
  for (const std::string& n : colormap_names()) {
    if (n == name) return;
  }
  throw ValueError("colormap", "'" + name + "' is not one of viridis, turbo");
}

Color colormap(const std::string& name, float t) {
  if (name == "viridis") return interpolate(kViridis, t);
  if (name == "turbo") return interpolate(kTurbo, t);
  check_colormap(name);
  return Color::Zero();
}

std::vector<uint8_t> colormap_table(const std::string& name) {
  check_colormap(name);
  std::vector<uint8_t> table(256 * 4);
  for (int i = 0; i < 256; ++i) {
    const Color c = colormap(name, static_cast<float>(i) / 255.0f);
    for (int k = 0; k < 3; ++k) {
      table[i * 4 + k] = static_cast<uint8_t>(std::lround(std::clamp(c[k], 0.0f, 1.0f) * 255.0f));
    }
    table[i * 4 + 3] = 255;
  }
  return table;
}

Color categorical_color(int64_t id) {
  if (id < 0) return Color(0.6f, 0.6f, 0.6f);
  const float* c = kTab10[id % 10];
  const float shade = std::pow(0.75f, static_cast<float>((id / 10) % 3));
  return Color(c[0] * shade, c[1] * shade, c[2] * shade);
}

std::vector<float> categorical_colors(const std::vector<int32_t>& ids) {
  std::vector<float> colors;
  colors.reserve(ids.size() * 3);
  for (int32_t id : ids) {
    const Color c = categorical_color(id);
    colors.insert(colors.end(), {c.x(), c.y(), c.z()});
  }
  return colors;
}

}  // namespace dynscope::render
