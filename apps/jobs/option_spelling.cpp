#include "jobs/option_spelling.h"

#include <algorithm>
#include <cctype>
#include <set>

#include "jobs/surface_kind.h"

namespace orthofront::jobs {

namespace {

const std::set<std::string>& option_names() {
  static const std::set<std::string> names = [] {
    std::set<std::string> all{"field", "seed"};
    for (const SurfaceKind kind : kSurfaceKinds) {
      const KindOptions options(kind);
      for (const OptionSpec& spec : options.set.specs()) all.insert(spec.name);
    }
    return all;
  }();
  return names;
}

std::string respelled(const std::string& name, OptionSpelling spelling) {
  if (spelling == OptionSpelling::python) return option_keyword(name);
  if (name == "field") return "the input";
  if (name == "seed") return "the seed";
  return option_label(name);
}

bool name_char(char c) {
  const auto u = static_cast<unsigned char>(c);
  return std::islower(u) || std::isdigit(u) || c == '-';
}

}  // namespace

std::string option_keyword(const std::string& name) {
  std::string keyword = name;
  std::replace(keyword.begin(), keyword.end(), '-', '_');
  return keyword;
}

std::string option_label(const std::string& name) {
  std::string label;
  bool upper = true;
  for (const char c : name) {
    if (c == '-') {
      label += ' ';
      upper = true;
      continue;
    }
    label += upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
    upper = false;
  }
  return label;
}

std::string spell_options(const std::string& message, OptionSpelling spelling) {
  if (spelling == OptionSpelling::command_line) return message;
  std::string out;
  std::size_t at = 0;
  while (at < message.size()) {
    const std::size_t dash = message.find("--", at);
    if (dash == std::string::npos) break;
    std::size_t end = dash + 2;
    while (end < message.size() && name_char(message[end])) ++end;
    std::string name = message.substr(dash + 2, end - dash - 2);
    while (!name.empty() && name.back() == '-') name.pop_back(), --end;  // "--steps-" is no name
    const bool starts_word = dash == 0 || !name_char(message[dash - 1]);
    out += message.substr(at, dash - at);
    if (starts_word && option_names().count(name) > 0)
      out += respelled(name, spelling);
    else
      out += message.substr(dash, end - dash);
    at = end;
  }
  out += message.substr(at);
  return out;
}

}  // namespace orthofront::jobs
