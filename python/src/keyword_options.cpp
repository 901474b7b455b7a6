#include "keyword_options.h"

#include <algorithm>
#include <string>
#include <vector>

namespace py = pybind11;

namespace orthofront::python {

namespace {

std::string option_name(std::string keyword) {
  std::replace(keyword.begin(), keyword.end(), '_', '-');
  return "--" + keyword;
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

py::list option_schema(const CLI::App& command) {
  py::list out;
  for (const CLI::Option* option : command.get_options()) {
    std::string flag = option->get_name();
    if (flag == "--help" || flag.rfind("--", 0) != 0 || option->get_group().empty()) continue;
    std::string keyword = flag.substr(2);
    std::replace(keyword.begin(), keyword.end(), '-', '_');
    py::dict entry;
    entry["name"] = keyword;
    entry["option"] = flag;
    entry["type"] = option->get_type_name();
    entry["default"] = option->get_default_str();
    entry["flag"] = option->get_expected_max() == 0;
    entry["help"] = option->get_description();
    out.append(entry);
  }
  return out;
}

void parse_keywords(CLI::App& command, const py::kwargs& options) {
  std::vector<std::string> tokens;
  for (const auto& [key, value] : options) {
    const std::string name = option_name(key.cast<std::string>());
    if (value.is_none()) continue;
    if (py::isinstance<py::bool_>(value)) {
      if (value.cast<bool>()) tokens.push_back(name);
      continue;
    }
    tokens.push_back(name);
    const py::object object = py::reinterpret_borrow<py::object>(value);
    if (py::isinstance<py::tuple>(object))
      tokens.push_back(joined(object, ":"));
    else if (py::isinstance<py::list>(object))
      tokens.push_back(joined(object, ","));
    else if (py::hasattr(object, "ndim") && object.attr("ndim").cast<int>() > 0)
      tokens.push_back(joined(object.attr("tolist")(), ","));  // a numpy array
    else
      tokens.push_back(value_text(object));
  }
  std::reverse(tokens.begin(), tokens.end());  // CLI11 takes a vector last argument first
  try {
    command.parse(tokens);
  } catch (const CLI::ExtrasError& e) {
    throw py::type_error(std::string("unexpected keyword argument: ") + e.what() +
                         " (keywords are the command-line options with '_' for '-')");
  } catch (const CLI::RequiredError& e) {
    throw py::type_error(std::string("missing keyword argument: ") + e.what());
  } catch (const CLI::ParseError& e) {
    throw py::value_error(e.what());
  }
}

}  // namespace orthofront::python
