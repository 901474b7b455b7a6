#include "orthofront/field/field_spec.h"

#include <array>
#include <charconv>
#include <cmath>
#include <system_error>

#include "orthofront/error.h"

namespace orthofront {

namespace {

std::string_view trim(std::string_view s) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// A finite number spelled entirely by `text` (an optional leading '+' is accepted).
bool parse_finite(std::string_view text, double& value) {
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
    if (!text.empty() && (text.front() == '+' || text.front() == '-')) return false;
  }
  if (text.empty()) return false;
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, value);
  return result.ec == std::errc() && result.ptr == end && std::isfinite(value);
}

std::string accepted_keys(std::span<const ParameterSpec> params) {
  if (params.empty()) return "none";
  std::string keys;
  for (const ParameterSpec& param : params) {
    if (!keys.empty()) keys += ", ";
    keys += param.name;
  }
  return keys;
}

double parse_value(const std::string& where, const ParameterSpec& param, std::string_view text) {
  double value = 0;
  if (!parse_finite(text, value)) throw InvalidArgument(where + ", expected a finite number");
  switch (param.kind) {
    case ParameterKind::real:
      break;
    case ParameterKind::positive:
      if (!(value > 0)) throw InvalidArgument(where + ", expected a number > 0");
      break;
    case ParameterKind::integer:
      if (value != std::floor(value) || value < param.lo || value > param.hi) {
        throw InvalidArgument(where + ", expected an integer from " + format_parameter(param.lo) +
                              " to " + format_parameter(param.hi));
      }
      break;
    case ParameterKind::flag:
      if (value != 0 && value != 1) throw InvalidArgument(where + ", expected 0 or 1");
      break;
  }
  return value;
}

}  // namespace

std::string_view field_spec_name(std::string_view spec) {
  return trim(spec.substr(0, spec.find(':')));
}

ParsedParameters parse_field_parameters(std::string_view spec, std::string_view kind,
                                        std::string_view field,
                                        std::span<const ParameterSpec> params) {
  const std::string prefix = std::string(kind) + " '" + std::string(field) + "'";
  ParsedParameters out;
  std::vector<bool> given(params.size(), false);
  for (const ParameterSpec& param : params) out.values.push_back(param.default_value);

  const std::size_t colon = spec.find(':');
  if (colon != std::string_view::npos) {
    std::string_view rest = spec.substr(colon + 1);
    while (true) {
      const std::size_t comma = rest.find(',');
      const std::string_view item = trim(rest.substr(0, comma));
      const std::size_t equals = item.find('=');
      if (equals == std::string_view::npos) {
        throw InvalidArgument(prefix + ": parameter '" + std::string(item) +
                              "' is not of the form key=value");
      }
      const std::string_view key = trim(item.substr(0, equals));
      const std::string_view text = trim(item.substr(equals + 1));
      std::size_t index = params.size();
      for (std::size_t i = 0; i < params.size(); ++i) {
        if (key == params[i].name) index = i;
      }
      if (index == params.size()) {
        throw InvalidArgument(prefix + " has no parameter '" + std::string(key) +
                              "'; accepted: " + accepted_keys(params));
      }
      if (given[index]) {
        throw InvalidArgument(prefix + ": parameter '" + std::string(key) + "' given twice");
      }
      given[index] = true;
      const std::string where =
          prefix + ": parameter '" + std::string(key) + "' has value '" + std::string(text) + "'";
      out.values[index] = parse_value(where, params[index], text);
      if (comma == std::string_view::npos) break;
      rest = rest.substr(comma + 1);
    }
  }

  out.description = std::string(field);
  for (std::size_t i = 0; i < params.size(); ++i) {
    out.description += (i == 0 ? ':' : ',');
    out.description += params[i].name;
    out.description += '=';
    out.description += format_parameter(out.values[i]);
  }
  return out;
}

std::string format_parameter(double value) {
  std::array<char, 64> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value,
                                    std::chars_format::general, 6);
  return std::string(buffer.data(), result.ptr);
}

}  // namespace orthofront
