// The front image: write per-front quantities over (s, step) as OpenEXR, read them back with
// OpenEXR's API and compare with values computed from the mesh here.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>

#include <cmath>
#include <map>

#include "io/grid_test_support.h"
#include "orthofront/error.h"
#include "orthofront/io/exr_front_image.h"
#include "orthofront/mesh/mesh.h"

using Catch::Matchers::Contains;
using orthofront::Mesh;
using orthofront::Vec3;
using namespace grid_test;

namespace {

/// Three stream lines from a seed of 4 vertices; step 2 gains an inserted line at s = 0.5 (which
/// has no predecessor) and the last line has stopped.
Mesh sample_mesh() {
  Mesh mesh;
  const double seed_s[4] = {0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0};
  for (int i = 0; i < 4; ++i)
    mesh.add_vertex(Vec3(seed_s[i], 0, 0), 0.0, 0.0, seed_s[i], 0.0, 0, 0);
  for (int i = 0; i < 4; ++i)
    mesh.add_vertex(Vec3(seed_s[i], 0.5 + 0.1 * i, 0), 0.25 + 0.05 * i, 0.1 * (i + 1), seed_s[i],
                    0.01 * i, 0, 1);
  const double step2_s[4] = {0.0, 1.0 / 3.0, 0.5, 2.0 / 3.0};
  for (int i = 0; i < 4; ++i) {
    mesh.add_vertex(Vec3(step2_s[i], 1.5 + 0.1 * i, 0.2), 0.75 + 0.05 * i, 0.2 * (i + 1),
                    step2_s[i], 0.02 * i, i < 2 ? 1 : 2, 2);
  }
  return mesh;
}

struct Image {
  int width = 0;
  int height = 0;
  std::map<std::string, std::vector<float>> channels;
  int s_bins = 0;
  int steps = 0;
};

Image read_exr(const fs::path& path) {
  Imf::InputFile file(path.c_str());
  const Imath::Box2i window = file.header().dataWindow();
  Image image;
  image.width = window.max.x - window.min.x + 1;
  image.height = window.max.y - window.min.y + 1;
  Imf::FrameBuffer buffer;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
    REQUIRE(it.channel().type == Imf::FLOAT);
    auto& data = image.channels[it.name()];
    data.assign(static_cast<std::size_t>(image.width * image.height), -1.0f);
    buffer.insert(it.name(), Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(data.data()), sizeof(float),
                                        sizeof(float) * static_cast<std::size_t>(image.width)));
  }
  file.setFrameBuffer(buffer);
  file.readPixels(window.min.y, window.max.y);
  image.s_bins = file.header().typedAttribute<Imf::IntAttribute>("orthofront.s_bins").value();
  image.steps = file.header().typedAttribute<Imf::IntAttribute>("orthofront.steps").value();
  return image;
}

/// The expected channels, computed the obvious way: vertices per pixel, then means.
std::map<std::string, std::vector<float>> expected_channels(const Mesh& mesh, int width, int height) {
  const std::size_t pixels = static_cast<std::size_t>(width * height);
  std::map<std::string, std::vector<double>> sum;
  std::map<std::string, std::vector<int>> count;
  for (const char* name : {"alpha", "error", "time", "speed", "dtime"}) {
    sum[name].assign(pixels, 0.0);
    count[name].assign(pixels, 0);
  }
  std::vector<float> coverage(pixels, 0.0f);
  std::vector<float> front(pixels, NAN);
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    const auto column = static_cast<std::size_t>(std::lround(mesh.s[i] * (width - 1)));
    const std::size_t p = static_cast<std::size_t>(mesh.step[i] * width) + column;
    coverage[p] += 1;
    front[p] = std::isnan(front[p]) ? static_cast<float>(mesh.front_id[i])
                                    : std::min(front[p], static_cast<float>(mesh.front_id[i]));
    const auto put_value = [&](const char* name, double v) {
      sum[name][p] += v;
      ++count[name][p];
    };
    put_value("alpha", mesh.alpha[i]);
    put_value("error", mesh.error[i]);
    put_value("time", mesh.time[i]);
    for (std::size_t j = 0; j < mesh.vertex_count(); ++j) {
      if (mesh.step[j] == mesh.step[i] - 1 && mesh.s[j] == mesh.s[i]) {
        const double dt = mesh.time[i] - mesh.time[j];
        put_value("dtime", dt);
        put_value("speed", (mesh.positions[i] - mesh.positions[j]).norm() / dt);
      }
    }
  }
  std::map<std::string, std::vector<float>> out;
  for (auto& [name, values] : sum) {
    auto& channel = out[name];
    channel.resize(pixels);
    for (std::size_t p = 0; p < pixels; ++p)
      channel[p] = count[name][p] > 0 ? static_cast<float>(values[p] / count[name][p]) : NAN;
  }
  out["coverage"] = coverage;
  out["front_id"] = front;
  return out;
}

}  // namespace

TEST_CASE("exr front image: channels read back equal the values computed from the mesh", "[exr]") {
  TempDir dir("exr");
  const Mesh mesh = sample_mesh();
  const int bins = GENERATE(0, 4, 7);
  INFO("s bins " << bins);
  orthofront::io::FrontImageOptions options;
  options.s_bins = bins;
  const auto summary = orthofront::io::write_front_image(mesh, dir / "front.exr", options);
  const int width = bins == 0 ? 4 : bins;  // 0: the widest front (4 vertices)
  CHECK(summary.width == width);
  CHECK(summary.height == 3);
  const Image image = read_exr(dir / "front.exr");
  CHECK(image.width == width);
  CHECK(image.height == 3);
  CHECK(image.s_bins == width);
  CHECK(image.steps == 3);
  const auto expected = expected_channels(mesh, width, 3);
  REQUIRE(image.channels.size() == expected.size());
  std::size_t covered = 0;
  for (const auto& [name, values] : expected) {
    INFO("channel " << name);
    REQUIRE(image.channels.count(name) == 1);
    CHECK(same_values(image.channels.at(name), values));
  }
  for (const float c : expected.at("coverage")) covered += c > 0 ? 1 : 0;
  CHECK(summary.covered == covered);
  // Spot checks by hand: step 1, s = 1/3 → speed 0.6 / 0.3 = 2 (bins 4: column 1).
  if (bins == 4) {
    CHECK(image.channels.at("speed")[4 + 1] == Approx((Vec3(0, 0.6, 0)).norm() / 0.3));
    CHECK(image.channels.at("dtime")[4 + 1] == Approx(0.3f));
    CHECK(std::isnan(image.channels.at("speed")[0 + 1]));  // the seed has no predecessor
  }
  // Nothing but the image in the folder (written atomically).
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir.path())) ++files;
  CHECK(files == 1);
}

TEST_CASE("exr front image: meshes without the attributes are refused", "[exr]") {
  TempDir dir("exr");
  Mesh mesh;
  mesh.positions.push_back(Vec3::Zero());
  CHECK_THAT(thrown<orthofront::InvalidArgument>([&] { orthofront::io::write_front_image(mesh, dir / "x.exr"); }),
             Contains("x.exr") && Contains("s and step"));
  CHECK_THAT(thrown<orthofront::InvalidArgument>([&] { orthofront::io::write_front_image(Mesh{}, dir / "y.exr"); }),
             Contains("no vertices"));
  CHECK_FALSE(fs::exists(dir / "x.exr"));
}
