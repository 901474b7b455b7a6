#include "cli/option_flags.h"

#include <string>

#include "orthofront/error.h"

namespace orthofront::cli {

using namespace jobs;

namespace {

// CLI11's style: the kind, and for a choice its words (TEXT:{exact,interpolate}).
std::string flag_type(const jobs::OptionSpec& spec) {
  std::string name = jobs::type_name(spec);
  if (spec.type != jobs::OptionType::choice) return name;
  std::string words;
  for (const std::string& c : spec.choices) words += (words.empty() ? "" : ",") + c;
  return name + ":{" + words + "}";
}

}  // namespace

void add_option_flags(CLI::App& command, const std::shared_ptr<jobs::OptionSet>& options) {
  for (const jobs::OptionSpec& spec : options->specs()) {
    const std::string flag = "--" + spec.name;
    const auto set = [options, name = spec.name, flag](const std::string& text) {
      try {
        options->set(name, text);
      } catch (const InvalidArgument& e) {
        throw CLI::ValidationError(flag, e.what());
      }
    };
    const std::string& doc = spec.doc;
    CLI::Option* option = nullptr;
    if (spec.type == jobs::OptionType::flag) {
      option = command.add_flag_callback(flag, [set]() { set("true"); }, doc);
    } else {
      option = command.add_option_function<std::string>(flag, set, doc);
      option->type_name(flag_type(spec));
      if (spec.show_default) option->default_str(spec.current());
    }
    if (spec.required) option->required();
    option->group(jobs::group_title(spec.group));
  }
}

}  // namespace orthofront::cli
