// Layering: lib/ depends on Eigen, oneTBB and the standard library only, and never prints.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

namespace fs = std::filesystem;

TEST_CASE("lib/ includes no I/O library header and never writes to stdout or stderr",
          "[layering]") {
  const fs::path lib = fs::path(ORTHOFRONT_SOURCE_DIR) / "lib";
  REQUIRE(fs::is_directory(lib));
  const std::regex forbidden_include(
      R"(#\s*include\s*[<"](hdf5|H5[A-Za-z]*|openvdb/|nanovdb/|OpenEXR/|Imath/|ImfHeader|vtk|netcdf|iostream|fstream|cstdio|stdio\.h|nlohmann/|CLI/)[^>"]*[>"])");
  const std::regex printing(R"(\b(std::cout|std::cerr|std::clog|printf\s*\(|fprintf\s*\(|puts\s*\(|std::exit|\bexit\s*\(|abort\s*\())");
  std::size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(lib)) {
    const auto ext = entry.path().extension();
    if (ext != ".h" && ext != ".cpp" && ext != ".cuh" && ext != ".cu") continue;
    ++files;
    std::ifstream in(entry.path());
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      const auto comment = line.find("//");
      const std::string code = comment == std::string::npos ? line : line.substr(0, comment);
      INFO(entry.path().string() << ":" << number << ": " << line);
      CHECK_FALSE(std::regex_search(code, forbidden_include));
      CHECK_FALSE(std::regex_search(code, printing));
    }
  }
  CHECK(files > 10);
}

namespace {

// Every #include line of the sources under `folder` matching `forbidden`, as "file:line: text".
std::vector<std::string> includes_matching(const fs::path& folder, const std::regex& forbidden) {
  std::vector<std::string> hits;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    const auto ext = entry.path().extension();
    if (ext != ".h" && ext != ".cpp" && ext != ".cxx") continue;
    std::ifstream in(entry.path());
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      if (std::regex_search(line, forbidden))
        hits.push_back(entry.path().string() + ":" + std::to_string(number) + ": " + line);
    }
  }
  return hits;
}

}  // namespace

TEST_CASE("the jobs layer, Python and the ParaView plugin never include the command line",
          "[layering]") {
  const fs::path source(ORTHOFRONT_SOURCE_DIR);
  // apps/jobs holds every front end's options and checks: no command-line parser in it.
  const std::regex command_line(R"(#\s*include\s*[<"](cli/|CLI/))");
  for (const char* folder : {"apps/jobs", "python/src", "paraview"}) {
    INFO(folder);
    REQUIRE(fs::is_directory(source / folder));
    const std::vector<std::string> hits = includes_matching(source / folder, command_line);
    std::string listed;
    for (const std::string& hit : hits) listed += hit + "\n";
    INFO(listed);
    CHECK(hits.empty());
  }
  // And Python links the jobs library, not the CLI's.
  std::ifstream cmake(source / "python" / "CMakeLists.txt");
  std::string text, line;
  while (std::getline(cmake, line)) text += line + "\n";
  CHECK(text.find("orthofront_cli") == std::string::npos);
  CHECK(text.find("orthofront_jobs") != std::string::npos);
  // Nor does the ParaView plugin.
  for (const char* file : {"paraview/CMakeLists.txt", "paraview/plugin/filters/CMakeLists.txt"}) {
    INFO(file);
    std::ifstream in(source / file);
    std::string plugin_text;
    while (std::getline(in, line)) plugin_text += line + "\n";
    CHECK(plugin_text.find("orthofront_cli") == std::string::npos);
    CHECK(plugin_text.find("orthofront_jobs") != std::string::npos);
  }
}
