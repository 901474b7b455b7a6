#pragma once
/// Messages name options as the command line spells them ("raise --cache-budget"): the library
/// below the front ends knows one name per option, the schema's. Python and ParaView users
/// cannot type a flag, so each of those front ends respells the options a message names its own
/// way before showing it.
#include <string>

namespace orthofront::jobs {

enum class OptionSpelling {
  command_line,  ///< --cache-budget (unchanged)
  python,        ///< cache_budget
  paraview,      ///< Cache Budget (the property's label)
};

/// An option's name as Python's keyword: "flat-split" -> "flat_split".
std::string option_keyword(const std::string& name);
/// An option's name as a label (ParaView's property): "flat-split" -> "Flat Split".
std::string option_label(const std::string& name);

/// `message` with every --NAME of an option some surface kind takes (and --field, --seed)
/// written in `spelling`; other text, and --words that name no option, stay as they are.
std::string spell_options(const std::string& message, OptionSpelling spelling);

}  // namespace orthofront::jobs
