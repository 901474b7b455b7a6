#include "orthofront/io/exr_front_image.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIntAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/error.h"

namespace orthofront::io {
namespace {

constexpr int kMaxWidth = 1 << 16;
constexpr int kMaxHeight = 1 << 24;

struct Channel {
  const char* name;
  std::vector<float> sum;    // then: the mean
  std::vector<int> count;    // values that went into the pixel
};

}  // namespace

FrontImageSummary write_front_image(const Mesh& mesh, const std::filesystem::path& path,
                                    const FrontImageOptions& options) {
  const std::size_t n = mesh.vertex_count();
  if (n == 0) throw InvalidArgument("cannot write " + path.string() + ": the mesh has no vertices");
  if (mesh.s.size() != n || mesh.step.size() != n) {
    throw InvalidArgument("cannot write " + path.string() +
                          ": the mesh has no s and step attributes per vertex (a surface read "
                          "from .obj, or not made by the engine?)");
  }
  const bool has_time = mesh.time.size() == n;
  const bool has_alpha = mesh.alpha.size() == n;
  const bool has_error = mesh.error.size() == n;
  const bool has_front = mesh.front_id.size() == n;
  if (options.s_bins < 0 || options.s_bins > kMaxWidth) {
    throw InvalidArgument("s bins " + std::to_string(options.s_bins) + " out of range [0, " +
                          std::to_string(kMaxWidth) + "]");
  }
  std::int32_t max_step = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (mesh.step[i] < 0) {
      throw InvalidArgument("cannot write " + path.string() + ": vertex " + std::to_string(i) +
                            " has the negative step " + std::to_string(mesh.step[i]));
    }
    max_step = std::max(max_step, mesh.step[i]);
  }
  if (max_step + 1 > kMaxHeight)
    throw InvalidArgument("cannot write " + path.string() + ": too many steps for an image");
  const int height = max_step + 1;
  int width = options.s_bins;
  if (width == 0) {
    std::vector<int> per_step(static_cast<std::size_t>(height), 0);
    for (std::size_t i = 0; i < n; ++i) ++per_step[static_cast<std::size_t>(mesh.step[i])];
    int widest = 1;
    for (const int count : per_step) widest = std::max(widest, count);
    width = std::min(widest, kMaxWidth);
  }

  // The predecessor on the same stream line: the vertex of step - 1 with the same s.
  std::map<std::pair<std::int32_t, double>, std::size_t> by_line;
  for (std::size_t i = 0; i < n; ++i) by_line.emplace(std::make_pair(mesh.step[i], mesh.s[i]), i);

  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<Channel> channels;
  for (const char* name : {"alpha", "error", "speed", "dtime", "time"})
    channels.push_back(Channel{name, std::vector<float>(pixels, 0.0f), std::vector<int>(pixels, 0)});
  std::vector<float> coverage(pixels, 0.0f);
  std::vector<float> front(pixels, std::numeric_limits<float>::quiet_NaN());
  std::vector<double> sums(pixels * channels.size(), 0.0);
  const auto add = [&](std::size_t channel, std::size_t pixel, double value) {
    if (!std::isfinite(value)) return;
    sums[channel * pixels + pixel] += value;
    ++channels[channel].count[pixel];
  };
  for (std::size_t i = 0; i < n; ++i) {
    const double s = std::clamp(mesh.s[i], 0.0, 1.0);
    if (!std::isfinite(mesh.s[i])) continue;
    const auto column = static_cast<std::size_t>(std::lround(s * (width - 1)));
    const std::size_t pixel = static_cast<std::size_t>(mesh.step[i]) * static_cast<std::size_t>(width) + column;
    coverage[pixel] += 1.0f;
    if (has_alpha) add(0, pixel, mesh.alpha[i]);
    if (has_error) add(1, pixel, mesh.error[i]);
    if (has_time) {
      add(4, pixel, mesh.time[i]);
      const auto prev = mesh.step[i] > 0 ? by_line.find({mesh.step[i] - 1, mesh.s[i]}) : by_line.end();
      if (prev != by_line.end()) {
        const double dt = mesh.time[i] - mesh.time[prev->second];
        add(3, pixel, dt);
        if (dt != 0.0) add(2, pixel, (mesh.positions[i] - mesh.positions[prev->second]).norm() / std::abs(dt));
      }
    }
    if (has_front) {
      const auto id = static_cast<float>(mesh.front_id[i]);
      if (std::isnan(front[pixel]) || id < front[pixel]) front[pixel] = id;
    }
  }
  FrontImageSummary summary;
  summary.width = width;
  summary.height = height;
  for (std::size_t c = 0; c < channels.size(); ++c) {
    for (std::size_t p = 0; p < pixels; ++p) {
      const int count = channels[c].count[p];
      channels[c].sum[p] = count > 0 ? static_cast<float>(sums[c * pixels + p] / count)
                                     : std::numeric_limits<float>::quiet_NaN();
    }
  }
  for (const float c : coverage) summary.covered += c > 0 ? 1 : 0;

  check_writable(path);
  const std::filesystem::path temp = temporary_path(path);
  try {
    Imf::Header header(width, height);
    header.compression() = Imf::ZIP_COMPRESSION;
    header.insert("orthofront.channels",
                  Imf::StringAttribute(
                      "rows: front steps 0..steps-1; columns: seed parameter s = column / (s_bins - 1); "
                      "alpha, error, time: means per pixel; speed: |dx|/dt to the previous vertex "
                      "of the stream line; dtime: dt per step; front_id: smallest front id; "
                      "coverage: vertices per pixel (0: no data, other channels NaN)"));
    header.insert("orthofront.s_bins", Imf::IntAttribute(width));
    header.insert("orthofront.steps", Imf::IntAttribute(height));
    Imf::FrameBuffer buffer;
    const std::size_t x_stride = sizeof(float);
    const std::size_t y_stride = sizeof(float) * static_cast<std::size_t>(width);
    const auto add_channel = [&](const char* name, std::vector<float>& data) {
      header.channels().insert(name, Imf::Channel(Imf::FLOAT));
      buffer.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(data.data()), x_stride, y_stride));
    };
    for (Channel& c : channels) add_channel(c.name, c.sum);
    add_channel("front_id", front);
    add_channel("coverage", coverage);
    {
      Imf::OutputFile file(temp.c_str(), header);
      file.setFrameBuffer(buffer);
      file.writePixels(height);
    }
    std::filesystem::rename(temp, path);
  } catch (const std::exception& e) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw IoError("cannot write " + path.string() + ": " + e.what());
  }
  return summary;
}

}  // namespace orthofront::io
