#pragma once
/// A comma-separated list of counts on a command line ("1e4,1e5,300"), as the benchmarks take
/// their particle counts and front sizes.
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "orthofront/error.h"

namespace orthofront::cli {

/// Throws InvalidArgument naming `option` and the item for one that is not a number in
/// [lo, hi], or for an empty list.
inline std::vector<std::size_t> parse_count_list(const std::string& text, const std::string& option,
                                                 double lo, double hi) {
  std::vector<std::size_t> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (end == item.c_str() || *end != '\0' || !(v >= lo) || v > hi) {
      std::ostringstream range;
      range << lo << " and " << hi;
      throw InvalidArgument(option + ": '" + item + "' is not a count between " + range.str());
    }
    out.push_back(static_cast<std::size_t>(std::llround(v)));
  }
  if (out.empty()) throw InvalidArgument(option + ": no count given");
  return out;
}

}  // namespace orthofront::cli
