// The `stream` subcommand end to end: files it writes, the summary, and bad input.
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <csignal>
#include <string>
#include <vector>

#include "orthofront/io/hdf5_layout.h"
#include "apps/cli_run.h"
#include "orthofront/io/mesh_io.h"
#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

struct Outcome {
  int status = 0;
  std::string output;  // stdout and stderr together
};

Outcome run(const std::string& args) {
  // One log per process: ctest runs the test cases of this file in parallel processes.
  const fs::path log =
      fs::temp_directory_path() / ("orthofront-stream-test-" + std::to_string(::getpid()) + ".log");
  const std::string command = std::string(ORTHOFRONT_BINARY) + " " + args + " > " + log.string() +
                              " 2>&1 < /dev/null";
  Outcome o;
  o.status = WEXITSTATUS(std::system(command.c_str()));
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  o.output = text.str();
  return o;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("orthofront-test-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

bool folder_is_empty(const fs::path& dir) { return fs::is_empty(dir); }

}  // namespace

TEST_CASE("stream writes the mesh, the report and a summary", "[cli][stream]") {
  const fs::path dir = fresh_dir("stream-ok");
  const Outcome o = run("stream --field saddle3d --seed line:-1,2,0.1:1,2,0.1 --seed-count 20 "
                        "--edge 0.1 --steps 30 --out " + (dir / "s.ply").string() + " --report " +
                        (dir / "s.json").string());
  REQUIRE(o.status == 0);
  CHECK(o.output.find("quads") != std::string::npos);
  CHECK(o.output.find((dir / "s.ply").string()) != std::string::npos);
  const orthofront::Mesh mesh = orthofront::io::read_mesh(dir / "s.ply");
  CHECK(mesh.vertex_count() > 300);
  for (const auto& p : mesh.positions) CHECK(std::abs(p.y() * p.z() - 0.2) < 1e-4);
  std::ifstream report(dir / "s.json");
  std::stringstream text;
  text << report.rdbuf();
  CHECK(text.str().find("\"stop_reason\"") != std::string::npos);
  CHECK(text.str().find("\"saddle3d\"") != std::string::npos);
  // Nothing but the two outputs (no temporary files left behind).
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++files;
  CHECK(files == 2);
}

TEST_CASE("stream rejects bad input naming the value, with no output file", "[cli][stream]") {
  struct Case {
    const char* what;
    std::string args;
    std::string named;  // must appear in the message
  };
  const fs::path dir = fresh_dir("stream-bad");
  const std::string out = " --out " + (dir / "x.vtp").string();
  const std::string good_seed = " --seed line:-1,2,0.1:1,2,0.1";
  const Case cases[] = {
      {"unknown field", "stream --field nosuchfield" + good_seed + out, "nosuchfield"},
      {"unknown parameter", "stream --field lorenz:rhoo=3" + good_seed + out, "rhoo"},
      {"malformed seed", "stream --field saddle3d --seed line:1,2:3" + out, "line:1,2:3"},
      {"unknown seed kind", "stream --field saddle3d --seed spiral:1" + out, "spiral"},
      {"zero seeds", "stream --field saddle3d --seed-count 0" + good_seed + out,
       "--seed-count must be at least 2, got 0"},
      {"one seed", "stream --field saddle3d --seed-count 1" + good_seed + out,
       "--seed-count must be at least 2, got 1"},
      {"seed outside the domain", "stream --field saddle3d --seed line:50,50,50:60,60,60" + out,
       "outside"},
      {"negative edge", "stream --field saddle3d --edge -0.1" + good_seed + out, "-0.1"},
      {"unwritable output", "stream --field saddle3d" + good_seed + " --out /nonexistent/dir/x.vtp",
       "/nonexistent/dir"},
      {"unknown extension", "stream --field saddle3d" + good_seed + " --out " +
                                (dir / "x.stl").string(), "x.stl"},
      {"missing seed file", "stream --field saddle3d --seed file:/nonexistent/seed.csv" + out,
       "/nonexistent/seed.csv"},
      {"more seeds than the vertex budget",
       "stream --field saddle3d --seed-count 100000000" + good_seed + out,
       "--seed-count 100000000 exceeds the vertex budget"},
      {"a negative seed-shot budget",
       "stream --field saddle3d --shot-evaluations -3" + good_seed + out,
       "--shot-evaluations: -3 is below 0"},
      {"an edge that would refine the seed past the vertex budget",
       "stream --field saddle3d --edge 1e-9" + good_seed + out, "raise --edge"},
  };
  for (const Case& c : cases) {
    const Outcome o = run(c.args);
    INFO(c.what << ": " << o.output);
    CHECK(o.status == 2);  // bad input (docs/user-guide.md); 3 would be an internal error
    CHECK(o.output.find(c.named) != std::string::npos);
    CHECK(folder_is_empty(dir));
  }
}

TEST_CASE("fields lists every analytic field with its domain", "[cli][fields]") {
  const Outcome o = run("fields");
  REQUIRE(o.status == 0);
  for (const char* name : {"saddle", "saddle3d", "sinus", "focus-sink", "lorenz", "stalling",
                           "repelling-node-saddle", "abc", "double-gyre"})
    CHECK(o.output.find(std::string(name) + "\n") != std::string::npos);
  CHECK(o.output.find("domain") != std::string::npos);
}

TEST_CASE("a seed in a field without data says so, not 'outside'", "[cli][stream]") {
  const fs::path dir = fresh_dir("stream-nodata");
  orthofront::VectorGrid zeros;
  zeros.geometry.dimension = 3;
  zeros.geometry.size = {6, 6, 6};
  zeros.values.assign(zeros.geometry.point_count() * 3, 0.0f);  // zero vectors: no data (land)
  orthofront::io::write_hdf5_grid(zeros, dir / "zeros.h5");
  const Outcome o = run("stream --field " + (dir / "zeros.h5").string() +
                        " --seed line:1,1,1:4,4,4 --out " + (dir / "x.vtp").string());
  INFO(o.output);
  CHECK(o.status == 2);
  CHECK(o.output.find("has no data") != std::string::npos);
  CHECK(o.output.find("(1, 1, 1)") != std::string::npos);
  CHECK(o.output.find("outside") == std::string::npos);
  CHECK_FALSE(fs::exists(dir / "x.vtp"));
}

TEST_CASE("an empty surface is written with a warning", "[cli][stream]") {
  const fs::path dir = fresh_dir("stream-empty");
  const Outcome o = run("stream --field saddle3d --seed line:-1,2,0.1:1,2,0.1 --steps 0 --out " +
                        (dir / "x.vtp").string());
  INFO(o.output);
  CHECK(o.status == 0);
  CHECK(o.output.find("warning: the surface has no faces (stopped: steps after 0 steps)") !=
        std::string::npos);
  CHECK(fs::exists(dir / "x.vtp"));
}

TEST_CASE("a seed along a stream line through a critical point gets a warning", "[cli][stream]") {
  // The saddle's x axis is a stream line through its critical point: the seed is carried along
  // itself and every face has no area.
  const fs::path dir = fresh_dir("stream-degenerate");
  const Outcome o = run("stream --field saddle --seed line:-1,0,0:1,0,0 --steps 20 --out " +
                        (dir / "x.vtp").string());
  INFO(o.output);
  CHECK(o.status == 0);
  CHECK(o.output.find("warning: 43 of 43 faces are degenerate (no area)") != std::string::npos);
  // Across the flow: no warning.
  const Outcome across = run("stream --field saddle --seed line:-1,1,0:1,1,0 --steps 20 --out " +
                             (dir / "y.vtp").string());
  CHECK(across.status == 0);
  CHECK(across.output.find("degenerate (no area)") == std::string::npos);
}

TEST_CASE("two runs writing the same mesh and report leave a matching pair", "[cli][stream]") {
  const fs::path dir = fresh_dir("stream-race");
  const std::string mesh = (dir / "s.vtp").string(), report = (dir / "s.json").string();
  for (int trial = 0; trial < 6; ++trial) {
    // Two surfaces of different sizes, started together.
    const std::string common = "' stream --field saddle3d --seed line:-1,2,0.1:1,2,0.1 --quiet"
                               " --out '" + mesh + "' --report '" + report + "'";
    // Both must succeed (the status is 0 only when both runs exit 0).
    const std::string both = "('" + std::string(ORTHOFRONT_BINARY) + common + " --seed-count 10 & a=$!; '" +
                             ORTHOFRONT_BINARY + common + " --seed-count 30 & b=$!; wait $a; ra=$?; "
                             "wait $b; rb=$?; [ $ra -eq 0 ] && [ $rb -eq 0 ]) >/dev/null 2>&1";
    REQUIRE(std::system(both.c_str()) == 0);
    std::ifstream in(report);
    std::stringstream text;
    text << in.rdbuf();
    const std::string json = text.str();
    const std::size_t at = json.find("\"vertices\":");
    REQUIRE(at != std::string::npos);
    const std::size_t vertices = std::stoul(json.substr(at + 11));
    CHECK(orthofront::io::read_mesh(mesh).vertex_count() == vertices);
  }
}


TEST_CASE("SIGTERM and SIGINT write the surface built so far, marked incomplete",
          "[cli][stream][signals]") {
  const fs::path dir = fresh_dir("stream-signal");
  // A long run: the Lorenz band at ℓ 0.25 until it leaves the domain, without the stall cut
  // (at ℓ 0.5 the whole surface could be finished before the signal came).
  const std::vector<std::string> args{"stream", "--field", "lorenz:reverse=1", "--seed",
                                      "circle:0,0,0:1.283,1,0:1", "--seed-count", "10", "--edge",
                                      "0.25", "--steps", "1000000", "--max-vertices", "100000000",
                                      "--stall-steps", "0",
                                      "--out", (dir / "s.vtp").string(), "--report",
                                      (dir / "s.json").string()};
  for (int signal : {SIGTERM, SIGINT}) {
    const pid_t pid = cli_test::start(args, (dir / "log.txt").string());
    ::usleep(1'500'000);
    ::kill(pid, signal);
    int status = 0;
    ::waitpid(pid, &status, 0);
    std::ifstream log(dir / "log.txt");
    std::stringstream text;
    text << log.rdbuf();
    INFO("signal " << signal << ": " << text.str());
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 2);
    CHECK(text.str().find("interrupted") != std::string::npos);
    // The partial surface is a whole mesh (read back in full), with faces, and its report says
    // it is incomplete; no temporary file is left beside them.
    const orthofront::Mesh mesh = orthofront::io::read_mesh(dir / "s.vtp");
    CHECK(mesh.vertex_count() > 100);
    CHECK(mesh.face_count() > 100);
    std::ifstream report(dir / "s.json");
    std::stringstream json;
    json << report.rdbuf();
    CHECK(json.str().find("\"complete\": false") != std::string::npos);
    for (const auto& entry : fs::directory_iterator(dir))
      CHECK(entry.path().filename().string().find(".tmp-") == std::string::npos);
  }
}

TEST_CASE("a surface stopped by the vertex budget says so, with the memory it used",
          "[cli][stream]") {
  const fs::path dir = fresh_dir("stream-budget");
  const Outcome o = run("stream --field lorenz:reverse=1 --seed circle:0,0,0:1.283,1,0:1 "
                        "--seed-count 10 --edge 0.5 --steps 500 --max-vertices 5000 --out " +
                        (dir / "s.vtp").string() + " --report " + (dir / "s.json").string());
  INFO(o.output);
  CHECK(o.status == 0);
  CHECK(o.output.find("warning: stopped at the vertex budget of 5000") != std::string::npos);
  CHECK(o.output.find("raise --max-vertices") != std::string::npos);
  std::ifstream report(dir / "s.json");
  std::stringstream json;
  json << report.rdbuf();
  CHECK(json.str().find("\"peak_rss_bytes\"") != std::string::npos);
}

TEST_CASE("stream --device: the front of a gridded field advances by bulk advection on the "
          "exact surface, and says what it cannot do",
          "[cli][stream][advect]") {
  const fs::path dir = fresh_dir("stream-device");
  const std::string h5 = (dir / "saddle.h5").string();
  REQUIRE(run("generate --field saddle3d --resolution 33,33,33 --out " + h5 + " --quiet").status ==
          0);
  const auto stream = [&](const std::string& name, const std::string& extra) {
    return run("stream --field " + h5 + " --seed line:-1,2,0.1:1,2,0.1 --seed-count 20 --edge 0.1 "
               "--steps 100 --out " + (dir / (name + ".ply")).string() + " --report " +
               (dir / (name + ".json")).string() + " " + extra);
  };
  const Outcome plain = stream("plain", "");
  INFO(plain.output);
  REQUIRE(plain.status == 0);
  const Outcome bulk = stream("bulk", "--device cpu");
  INFO(bulk.output);
  REQUIRE(bulk.status == 0);
  // A linear field is exact on its grid: both advances stay on y z = 0.2.
  const orthofront::Mesh a = orthofront::io::read_mesh(dir / "plain.ply");
  const orthofront::Mesh b = orthofront::io::read_mesh(dir / "bulk.ply");
  CHECK(b.vertex_count() == a.vertex_count());
  for (const auto& p : b.positions) REQUIRE(std::abs(p.y() * p.z() - 0.2) < 1e-8);
  std::ifstream report(dir / "bulk.json");
  const auto j = nlohmann::json::parse(report);
  CHECK(j["device"]["backend"] == "cpu");
  CHECK(j["device"]["calls"].get<std::size_t>() >= j["steps"].get<std::size_t>());
  // auto with fronts below the break-even size: the per-vertex surface, byte for byte.
  REQUIRE(stream("auto", "--device auto").status == 0);
  std::ifstream pa(dir / "plain.ply", std::ios::binary), aa(dir / "auto.ply", std::ios::binary);
  std::stringstream plain_bytes, auto_bytes;
  plain_bytes << pa.rdbuf();
  auto_bytes << aa.rdbuf();
  CHECK(plain_bytes.str() == auto_bytes.str());
  // An analytic field has no grid to move particles through.
  const Outcome analytic = run("stream --field saddle3d --seed line:-1,2,0.1:1,2,0.1 --steps 5 "
                               "--device cpu --out " + (dir / "a.ply").string());
  CHECK(analytic.status == 2);
  CHECK(analytic.output.find("--device") != std::string::npos);
  CHECK(!fs::exists(dir / "a.ply"));
  // Without a CUDA device (or a CUDA build), --device cuda says why and writes nothing.
  const Outcome cuda = stream("cuda", "--device cuda");
  if (cuda.status != 0) {
    CHECK(cuda.status == 2);
    CHECK(cuda.output.find("--device cuda:") != std::string::npos);
    CHECK(!fs::exists(dir / "cuda.ply"));
  }
}

TEST_CASE("a run whose rows alone would pass the vertex cap is warned of before it starts",
          "[cli][stream]") {
  const fs::path dir = fresh_dir("stream-cap-warning");
  const std::string out = (dir / "s.vtp").string();
  // 2 long at edge 0.01: about 201 vertices a row, 200 rows, 40,200 against a cap of 5,000.
  const Outcome r = run("stream --field sinus --seed line:-1,0,0:1,0,0 --edge 0.01 "
                        "--steps 200 --max-vertices 5000 --quiet --out " + out);
  INFO(r.output);
  CHECK(r.status == 0);
  CHECK(r.output.find("warning: the seed is 2 long: at --edge 0.01 each front has about 201 "
                      "vertices, and 200 steps would make about 4.02e+04, past the vertex cap of "
                      "5000") != std::string::npos);
  CHECK(r.output.find("the domain's diagonal over 300") != std::string::npos);
  // Within the cap: no such warning.
  const Outcome fine = run("stream --field sinus --seed line:-1,0,0:1,0,0 --edge 0.05 "
                           "--steps 50 --quiet --out " + out);
  INFO(fine.output);
  CHECK(fine.status == 0);
  CHECK(fine.output.find("past the vertex cap") == std::string::npos);
}
