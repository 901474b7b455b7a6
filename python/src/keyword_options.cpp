#include "keyword_options.h"

#include <pybind11/stl.h>

#include <algorithm>
#include <string>

#include "jobs/option_spelling.h"
#include "orthofront/error.h"

namespace py = pybind11;

namespace orthofront::python {

namespace {

std::string option_of(std::string keyword) {
  std::replace(keyword.begin(), keyword.end(), '_', '-');
  return keyword;
}

std::string value_text(py::object value) {
  if (py::hasattr(value, "item")) value = value.attr("item")();  // a numpy scalar
  // repr() of a float is its shortest round-trip form: the option gets the exact double.
  if (py::isinstance<py::float_>(value)) return py::repr(value).cast<std::string>();
  return py::str(value).cast<std::string>();
}

std::string joined(const py::sequence& items, const char* separator) {
  std::string text;
  for (const py::handle item : items)
    text += (text.empty() ? "" : separator) + value_text(py::reinterpret_borrow<py::object>(item));
  return text;
}

}  // namespace

py::list option_schema(const jobs::OptionSet& options) {
  py::list out;
  for (const jobs::OptionSpec& spec : options.specs()) {
    py::dict entry;
    entry["name"] = jobs::option_keyword(spec.name);
    entry["option"] = "--" + spec.name;
    entry["type"] = jobs::type_name(spec);
    entry["default"] = spec.show_default ? spec.current() : std::string();
    entry["flag"] = spec.type == jobs::OptionType::flag;
    entry["help"] = spec.doc;
    entry["unit"] = spec.unit;
    entry["group"] = jobs::group_title(spec.group);
    entry["choices"] = spec.choices;
    entry["required"] = spec.required;
    out.append(entry);
  }
  return out;
}

void parse_keywords(jobs::OptionSet& options, const py::kwargs& keywords) {
  for (const auto& [key, value] : keywords) {
    const std::string keyword = key.cast<std::string>();
    const std::string name = option_of(keyword);
    const jobs::OptionSpec* spec = options.find(name);
    if (spec == nullptr)
      throw py::type_error("unexpected keyword argument '" + keyword +
                           "' (keywords are the command-line options with '_' for '-')");
    if (value.is_none()) continue;
    const py::object object = py::reinterpret_borrow<py::object>(value);
    if (spec->type != jobs::OptionType::flag && py::isinstance<py::bool_>(object))
      throw py::type_error(keyword + ": takes a value, not True or False");
    std::string text;
    if (py::isinstance<py::bool_>(object))
      text = object.cast<bool>() ? "true" : "false";
    else if (py::isinstance<py::tuple>(object))
      text = joined(object, ":");
    else if (py::isinstance<py::list>(object))
      text = joined(object, ",");
    else if (py::hasattr(object, "ndim") && object.attr("ndim").cast<int>() > 0)
      text = joined(object.attr("tolist")(), ",");  // a numpy array
    else
      text = value_text(object);
    try {
      options.set(name, text);
    } catch (const InvalidArgument& e) {
      throw py::value_error(keyword + ": " + e.what());
    }
  }
  const std::vector<std::string> missing = options.missing();
  if (!missing.empty())
    throw py::type_error("missing keyword argument: " + jobs::option_keyword(missing.front()));
}

}  // namespace orthofront::python
