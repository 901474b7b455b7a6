// Layering: lib/ depends on Eigen, oneTBB and the standard library only, and never prints.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

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
