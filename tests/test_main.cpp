#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cstdlib>

int main(int argc, char* argv[]) {
  // Commands the tests start draw no report histograms (each would start Python, and cases check
  // which files a run leaves): under ctest, which sets this too, and in a direct run alike.
  ::setenv("ORTHOFRONT_HISTOGRAMS", "0", 0);
  return Catch::Session().run(argc, argv);
}
