#include "jobs/option_set.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <system_error>

#include "orthofront/error.h"

namespace orthofront::jobs {

namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

// The whole of `text` as a T (std::from_chars: no locale, no leading blanks, no trailing rest).
template <class T>
T parse_number(const std::string& text, const char* what) {
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  if (begin != end && *begin == '+') ++begin;
  T value{};
  const auto [rest, error] = std::from_chars(begin, end, value);
  if (error == std::errc::result_out_of_range)
    throw InvalidArgument("'" + text + "' is out of range for " + what);
  if (error != std::errc() || rest != end || begin == end)
    throw InvalidArgument("'" + text + "' is not " + what);
  return value;
}

// The shortest text that reads back as the same double (a default shown is the value taken).
std::string number_text(double value) {
  std::array<char, 64> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}

}  // namespace

const char* group_title(OptionGroup group) {
  switch (group) {
    case OptionGroup::input: return "Input";
    case OptionGroup::algorithm: return "Algorithm";
    case OptionGroup::budget: return "Budget";
    case OptionGroup::output: return "Output";
    case OptionGroup::performance: return "Performance";
  }
  return "";
}

const char* type_name(const OptionSpec& spec) {
  switch (spec.type) {
    case OptionType::real: return "FLOAT";
    case OptionType::integer: return "INT";
    case OptionType::count: return "UINT";
    case OptionType::flag: return "BOOL";
    case OptionType::choice:
    case OptionType::text: return "TEXT";
  }
  return "TEXT";
}

std::size_t choice_index(const std::vector<std::string>& choices, const std::string& text) {
  const std::string wanted = lower(text);
  for (std::size_t i = 0; i < choices.size(); ++i)
    if (lower(choices[i]) == wanted) return i;
  std::string words;
  for (const std::string& c : choices) words += (words.empty() ? "" : ", ") + c;
  throw InvalidArgument("'" + text + "' is not one of " + words);
}

OptionSpec& OptionSet::Adder::spec() { return set_.specs_[index_]; }

OptionSet::Adder& OptionSet::Adder::doc(std::string text) {
  spec().doc = std::move(text);
  return *this;
}
OptionSet::Adder& OptionSet::Adder::unit(std::string text) {
  spec().unit = std::move(text);
  return *this;
}
OptionSet::Adder& OptionSet::Adder::group(OptionGroup g) {
  spec().group = g;
  return *this;
}
OptionSet::Adder& OptionSet::Adder::required() {
  spec().required = true;
  return *this;
}
OptionSet::Adder& OptionSet::Adder::derived_default() {
  spec().show_default = false;
  return *this;
}

OptionSet::Adder& OptionSet::Adder::check(std::function<void(double, const std::string&)> test) {
  OptionSpec& s = spec();
  s.assign = [parse = s.assign, value = s.number, test = std::move(test)](const std::string& text) {
    parse(text);
    test(value(), text);
  };
  return *this;
}
OptionSet::Adder& OptionSet::Adder::range(double lo, double hi) {
  spec().lo = lo;
  spec().hi = hi >= 1e300 ? std::numeric_limits<double>::infinity() : hi;
  return check([lo, hi](double v, const std::string& text) {
    if (v >= lo && v <= hi) return;
    if (hi >= 1e300) throw InvalidArgument(text + " is below " + number_text(lo));
    throw InvalidArgument(text + " is not in the range " + number_text(lo) + " to " +
                          number_text(hi));
  });
}
OptionSet::Adder& OptionSet::Adder::between(double lo, double hi) {
  spec().lo = lo, spec().hi = hi;
  spec().lo_open = spec().hi_open = true;
  return check([lo, hi](double v, const std::string& text) {
    if (!(v > lo && v < hi))
      throw InvalidArgument(text + " is not strictly between " + number_text(lo) + " and " +
                            number_text(hi));
  });
}
OptionSet::Adder& OptionSet::Adder::at_least(double lo) { return range(lo, 1e308); }
OptionSet::Adder& OptionSet::Adder::positive() {
  spec().lo = 0;
  spec().lo_open = true;
  return check([](double v, const std::string& text) {
    if (!(v > 0)) throw InvalidArgument(text + " is not a positive number");
  });
}
OptionSet::Adder& OptionSet::Adder::one_of(std::vector<std::string> words) {
  OptionSpec& s = spec();
  s.type = OptionType::choice;
  s.choices = std::move(words);
  auto parse = s.assign;
  const std::vector<std::string> choices = s.choices;
  s.assign = [parse, choices](const std::string& text) {
    // As typed: these words are file-like names (cpu, cuda), compared exactly.
    if (std::find(choices.begin(), choices.end(), text) == choices.end()) {
      std::string list;
      for (const std::string& c : choices) list += (list.empty() ? "" : ", ") + c;
      throw InvalidArgument("'" + text + "' is not one of " + list);
    }
    parse(text);
  };
  return *this;
}

OptionSet::Adder OptionSet::add(OptionSpec spec) {
  if (index_.count(spec.name) > 0)
    throw InvalidArgument("option '" + spec.name + "' is defined twice");
  index_[spec.name] = specs_.size();
  specs_.push_back(std::move(spec));
  return Adder(*this, specs_.size() - 1);
}

OptionSet::Adder OptionSet::real(const std::string& name, double& member, std::string doc) {
  OptionSpec s;
  s.name = name;
  s.doc = std::move(doc);
  s.type = OptionType::real;
  s.current = [&member]() { return number_text(member); };
  s.assign = [&member](const std::string& text) {
    const double v = parse_number<double>(text, "a number");
    if (std::isnan(v)) throw InvalidArgument("'" + text + "' is not a number");
    member = v;
  };
  s.number = [&member]() { return member; };
  return add(std::move(s));
}

OptionSet::Adder OptionSet::integer(const std::string& name, int& member, std::string doc) {
  OptionSpec s;
  s.name = name;
  s.doc = std::move(doc);
  s.type = OptionType::integer;
  s.current = [&member]() { return std::to_string(member); };
  s.assign = [&member](const std::string& text) { member = parse_number<int>(text, "an integer"); };
  s.number = [&member]() { return static_cast<double>(member); };
  return add(std::move(s));
}

OptionSet::Adder OptionSet::count(const std::string& name, std::size_t& member, std::string doc) {
  OptionSpec s;
  s.name = name;
  s.doc = std::move(doc);
  s.type = OptionType::count;
  s.current = [&member]() { return std::to_string(member); };
  s.assign = [&member](const std::string& text) {
    member = parse_number<std::size_t>(text, "a whole number >= 0");
  };
  s.number = [&member]() { return static_cast<double>(member); };
  return add(std::move(s));
}

OptionSet::Adder OptionSet::text(const std::string& name, std::string& member, std::string doc) {
  OptionSpec s;
  s.name = name;
  s.doc = std::move(doc);
  s.type = OptionType::text;
  s.current = [&member]() { return member; };
  s.assign = [&member](const std::string& text) { member = text; };
  return add(std::move(s));
}

OptionSet::Adder OptionSet::flag(const std::string& name, bool& member, std::string doc,
                                 bool when_given) {
  OptionSpec s;
  s.name = name;
  s.doc = std::move(doc);
  s.type = OptionType::flag;
  s.current = [&member, when_given]() { return member == when_given ? "true" : "false"; };
  s.assign = [&member, when_given](const std::string& text) {
    const std::string t = lower(text);
    if (t == "true" || t == "1" || t == "on" || t == "yes")
      member = when_given;
    else if (t == "false" || t == "0" || t == "off" || t == "no")
      member = !when_given;
    else
      throw InvalidArgument("'" + text + "' is not true or false");
  };
  return add(std::move(s));
}

const OptionSpec* OptionSet::find(const std::string& name) const {
  const auto it = index_.find(name);
  return it == index_.end() ? nullptr : &specs_[it->second];
}

void OptionSet::set(const std::string& name, const std::string& text) {
  const OptionSpec* spec = find(name);
  if (spec == nullptr) throw InvalidArgument("no such option");
  spec->assign(text);
  given_.insert(name);
}

std::vector<std::string> OptionSet::missing() const {
  std::vector<std::string> out;
  for (const OptionSpec& s : specs_)
    if (s.required && !given(s.name)) out.push_back(s.name);
  return out;
}

}  // namespace orthofront::jobs
