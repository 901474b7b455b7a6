#pragma once
/// The options of a job, written once: each option's name, member, default, check, one-line doc,
/// unit and group. The command line's flags (cli/option_flags.h) and Python's keyword arguments
/// (python/src/keyword_options.h) are made from it, so they take the same names, defaults and
/// checks; each front end spells the names its own way (--flat-split, flat_split).
#include <cstddef>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace orthofront::jobs {

/// What an option is about, for help pages and property panels.
enum class OptionGroup { input, algorithm, budget, output, performance };

/// The group's name as help pages title it.
const char* group_title(OptionGroup group);

/// The kind of value an option takes.
enum class OptionType { real, integer, count, text, choice, flag };

struct OptionSpec {
  std::string name;             ///< words joined by '-': "flat-split"
  std::string doc;              ///< one line, or a short paragraph
  OptionType type = OptionType::text;
  OptionGroup group = OptionGroup::algorithm;
  std::string unit;             ///< e.g. "edge lengths", "s"; empty when none
  std::vector<std::string> choices;  ///< OptionType::choice: the accepted words
  bool required = false;
  bool show_default = true;     ///< false: the default is derived (from the data, --memory...)
  /// The member's value as text now (before parsing: the default).
  std::function<std::string()> current;
  /// Parses `text` into the member; throws InvalidArgument saying what is wrong with the value
  /// (each front end puts its own spelling of the name in front).
  std::function<void(const std::string& text)> assign;
  /// Numbers: the member's value (for the range checks).
  std::function<double()> number;
  /// Numbers: the accepted range as the checks state it, for panels that show one (-inf/inf
  /// where open-ended; lo_open/hi_open: the bound itself is refused).
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
};

/// A job kind's options, bound to the members of one arguments struct (which must outlive it).
class OptionSet {
 public:
  /// Adds an option and returns it for the fluent setters below.
  class Adder {
   public:
    Adder& doc(std::string text);
    Adder& unit(std::string text);
    Adder& group(OptionGroup g);
    Adder& required();
    Adder& derived_default();   ///< no default shown: it comes from elsewhere
    /// Numbers: the accepted range (inclusive).
    Adder& at_least(double lo);
    Adder& positive();          ///< > 0
    Adder& range(double lo, double hi);
    /// Numbers: strictly between lo and hi.
    Adder& between(double lo, double hi);
    /// Text: one of these words.
    Adder& one_of(std::vector<std::string> words);

   private:
    friend class OptionSet;
    /// Numbers: after parsing, `test(value, text)` throws InvalidArgument for a value refused.
    Adder& check(std::function<void(double, const std::string&)> test);
    Adder(OptionSet& set, std::size_t index) : set_(set), index_(index) {}
    OptionSpec& spec();
    OptionSet& set_;
    std::size_t index_;
  };

  Adder real(const std::string& name, double& member, std::string doc);
  Adder integer(const std::string& name, int& member, std::string doc);
  Adder count(const std::string& name, std::size_t& member, std::string doc);
  Adder text(const std::string& name, std::string& member, std::string doc);
  /// A word that selects an enumerator (case-insensitive, as typed): `words` maps each to it.
  template <class Enum>
  Adder choice(const std::string& name, Enum& member, std::vector<std::pair<std::string, Enum>> words,
               std::string doc);
  /// A switch: given, `member` becomes `when_given` (true for --warm, false for --no-rip).
  Adder flag(const std::string& name, bool& member, std::string doc, bool when_given = true);

  const std::vector<OptionSpec>& specs() const { return specs_; }
  const OptionSpec* find(const std::string& name) const;
  /// Parses a value given under `name` (a flag takes "true" or "false") and remembers that it was
  /// given. Throws InvalidArgument for an unknown name or a bad value, with the reason alone.
  void set(const std::string& name, const std::string& text);
  /// Whether `name` was given (by set()).
  bool given(const std::string& name) const { return given_.count(name) > 0; }
  /// Marks `name` given (a front end that assigned it itself).
  void mark_given(const std::string& name) { given_.insert(name); }
  /// The required options not given, in the order they were added.
  std::vector<std::string> missing() const;

 private:
  Adder add(OptionSpec spec);
  std::vector<OptionSpec> specs_;
  std::map<std::string, std::size_t> index_;
  std::set<std::string> given_;
  friend class Adder;
};

/// The value's kind as help pages name it: FLOAT, INT, UINT, TEXT, BOOL (a choice: TEXT).
const char* type_name(const OptionSpec& spec);

/// Which of `choices` `text` is (ignoring case); throws InvalidArgument listing them.
std::size_t choice_index(const std::vector<std::string>& choices, const std::string& text);

template <class Enum>
OptionSet::Adder OptionSet::choice(const std::string& name, Enum& member,
                                   std::vector<std::pair<std::string, Enum>> words,
                                   std::string doc) {
  OptionSpec spec;
  spec.name = name;
  spec.doc = std::move(doc);
  spec.type = OptionType::choice;
  for (const auto& w : words) spec.choices.push_back(w.first);
  auto table = std::make_shared<std::vector<std::pair<std::string, Enum>>>(std::move(words));
  spec.current = [table, &member]() {
    for (const auto& [word, value] : *table)
      if (value == member) return word;
    return std::string();
  };
  spec.assign = [table, &member, choices = spec.choices](const std::string& text) {
    member = (*table)[choice_index(choices, text)].second;
  };
  return add(std::move(spec));
}

}  // namespace orthofront::jobs
