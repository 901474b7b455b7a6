// libFuzzer entry point of one target; ORTHOFRONT_FUZZ_TARGET names it (see exercise.h).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "exercise.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  if (!orthofront::fuzz::exercise(ORTHOFRONT_FUZZ_TARGET, input)) __builtin_trap();
  return 0;
}
