// Writes the ParaView plugin's server-manager XML and each filter's setter header from the
// surface kinds' option schemas (jobs/surface_kind.h), so that the panel's properties are the
// command line's flags, with the same names, defaults, ranges and documentation.
//
//   orthofront-paraview-properties xml OUT.xml
//   orthofront-paraview-properties header KIND OUT.h
#include <charconv>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "jobs/surface_kind.h"
#include "orthofront/io/xml_text.h"
#include "paraview_names.h"

namespace {

using orthofront::jobs::KindOptions;
using orthofront::jobs::OptionGroup;
using orthofront::jobs::OptionSpec;
using orthofront::jobs::OptionType;
using orthofront::jobs::SurfaceKind;
namespace pv = orthofront::paraview;


// The shortest text that reads back as exactly `value`.
std::string number(double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

// The panel's default: the schema's, or the "from the data" value where the schema's comes from
// the data or the machine.
std::string panel_default(const OptionSpec& spec) {
  if (pv::from_data(spec)) return spec.type == OptionType::text ? "" : "0";
  const std::string current = spec.current ? spec.current() : "";
  switch (spec.type) {
    case OptionType::flag: return current == "true" ? "1" : "0";
    case OptionType::choice:
      for (std::size_t i = 0; i < spec.choices.size(); ++i)
        if (spec.choices[i] == current) return std::to_string(i);
      return "0";
    default: return current;
  }
}

// The help's figures of this machine ("now 23.0 GiB") do not belong in a plugin built here and
// run elsewhere: they go.
std::string without_figures_of_now(std::string doc) {
  for (const std::string mark : {"; the figure shown is for the memory available now", ", now "}) {
    for (std::size_t at = doc.find(mark); at != std::string::npos; at = doc.find(mark, at)) {
      const std::size_t end = mark == ", now " ? doc.find(')', at) : at + mark.size();
      doc.erase(at, (end == std::string::npos ? doc.size() : end) - at);
    }
  }
  return doc;
}

std::string documentation(const OptionSpec& spec) {
  std::string doc = without_figures_of_now(spec.doc);
  if (!spec.unit.empty() && doc.find(spec.unit) == std::string::npos) doc += " (" + spec.unit + ")";
  if (!doc.empty() && doc.back() != '.') doc += ".";
  if (pv::from_data(spec))
    doc += spec.type == OptionType::text ? " Empty: " + pv::from_data_meaning(spec) + "."
                                         : " 0: " + pv::from_data_meaning(spec) + ".";
  if (std::isfinite(spec.lo) || std::isfinite(spec.hi)) {
    doc += pv::from_data(spec) ? " Otherwise: " : " Accepted: ";
    if (std::isfinite(spec.lo) && std::isfinite(spec.hi))
      doc += (spec.lo_open ? "greater than " : "from ") + number(spec.lo) +
             (spec.hi_open ? ", less than " : " to ") + number(spec.hi);
    else if (std::isfinite(spec.lo))
      doc += (spec.lo_open ? "greater than " : "at least ") + number(spec.lo);
    else
      doc += (spec.hi_open ? "less than " : "at most ") + number(spec.hi);
    doc += ".";
  }
  doc += " Command line: --" + spec.name + ".";
  return doc;
}

void write_property(std::ostream& out, const OptionSpec& spec) {
  const std::string name = pv::property_name(spec.name);
  const std::string attributes = " name=\"" + name + "\" label=\"" + pv::property_label(spec.name) +
                                 "\" command=\"Set" + name + "\" number_of_elements=\"1\"" +
                                 " default_values=\"" + orthofront::io::xml_escaped(panel_default(spec)) + "\"" +
                                 (pv::shown_by_default(spec) ? "" : " panel_visibility=\"advanced\"");
  const auto range = [&](const char* domain) {
    if (!std::isfinite(spec.lo) && !std::isfinite(spec.hi)) return;
    out << "        <" << domain << " name=\"range\"";
    if (std::isfinite(spec.lo)) out << " min=\"" << number(spec.lo) << "\"";
    if (std::isfinite(spec.hi)) out << " max=\"" << number(spec.hi) << "\"";
    out << " />\n";
  };
  switch (spec.type) {
    case OptionType::real:
      out << "      <DoubleVectorProperty" << attributes << ">\n";
      range("DoubleRangeDomain");
      break;
    case OptionType::integer:
      out << "      <IntVectorProperty" << attributes << ">\n";
      range("IntRangeDomain");
      break;
    case OptionType::count:
      // ParaView has no range domain for 64-bit ids: the documentation states the range, and
      // the schema refuses a value out of it when the filter runs.
      out << "      <IdTypeVectorProperty" << attributes << ">\n";
      break;
    case OptionType::flag:
      out << "      <IntVectorProperty" << attributes << ">\n        <BooleanDomain name=\"bool\" />\n";
      break;
    case OptionType::choice:
      out << "      <IntVectorProperty" << attributes << ">\n        <EnumerationDomain name=\"enum\">\n";
      for (std::size_t i = 0; i < spec.choices.size(); ++i)
        out << "          <Entry value=\"" << i << "\" text=\"" << orthofront::io::xml_escaped(spec.choices[i])
            << "\" />\n";
      out << "        </EnumerationDomain>\n";
      break;
    case OptionType::text:
      out << "      <StringVectorProperty" << attributes << ">\n";
      break;
  }
  out << "        <Documentation>" << orthofront::io::xml_escaped(documentation(spec)) << "</Documentation>\n";
  const char* element = spec.type == OptionType::real      ? "DoubleVectorProperty"
                        : spec.type == OptionType::count   ? "IdTypeVectorProperty"
                        : spec.type == OptionType::text    ? "StringVectorProperty"
                                                           : "IntVectorProperty";
  out << "      </" << element << ">\n";
}

// A seed line end: a point of the input's bounds (its lowest or highest corner by default).
void write_seed_point(std::ostream& out, int end, const char* default_mode, const char* corner) {
  out << "      <DoubleVectorProperty name=\"Point" << end << "\" label=\"Seed Point " << end
      << "\" command=\"SetPoint" << end << "\"\n          number_of_elements=\"3\" "
      << "default_values=\"" << (end == 1 ? "0 0 0" : "1 0 0") << "\">\n"
      << "        <BoundsDomain name=\"range\" mode=\"normal\" default_mode=\"" << default_mode
      << "\">\n          <RequiredProperties>\n            <Property name=\"Input\" "
      << "function=\"Input\" />\n          </RequiredProperties>\n        </BoundsDomain>\n"
      << "        <Documentation>The seed line's " << (end == 1 ? "first" : "second")
      << " end (world units); by default the input's " << corner
      << " corner. Command line: --seed line:P1:P2.</Documentation>\n"
      << "      </DoubleVectorProperty>\n";
}

// The input, its vector array and the seed line: the filter's own properties.
void write_input_properties(std::ostream& out) {
  out << R"(      <InputProperty name="Input" command="SetInputConnection">
        <ProxyGroupDomain name="groups">
          <Group name="sources" />
          <Group name="filters" />
        </ProxyGroupDomain>
        <DataTypeDomain name="input_type">
          <DataType value="vtkImageData" />
          <DataType value="vtkRectilinearGrid" />
        </DataTypeDomain>
        <InputArrayDomain name="input_vectors" attribute_type="point" />
        <Documentation>Image data or a rectilinear grid (3D, or one point thick in z: a 2D flow
        in x, y) with a point vector array.</Documentation>
      </InputProperty>
      <StringVectorProperty name="SelectInputVectors" label="Vectors"
          command="SetInputArrayToProcess" number_of_elements="5" element_types="0 0 0 0 2"
          animateable="0">
        <ArrayListDomain name="array_list" attribute_type="Vectors"
            input_domain_name="input_vectors">
          <RequiredProperties>
            <Property name="Input" function="Input" />
          </RequiredProperties>
        </ArrayListDomain>
        <Documentation>The velocity: a point array of 3 components (of which a 2D flow uses x
        and y).</Documentation>
      </StringVectorProperty>
)";
  write_seed_point(out, 1, "min", "lowest");
  write_seed_point(out, 2, "max", "highest");
  out << R"(      <PropertyGroup label="Seed Line" panel_widget="InteractiveLine">
        <Property name="Point1" function="Point1WorldPosition" />
        <Property name="Point2" function="Point2WorldPosition" />
        <Property name="Input" function="Input" />
      </PropertyGroup>
      <IntVectorProperty name="ZerosAreNoData" label="Zeros Are No Data"
          command="SetZerosAreNoData" number_of_elements="1" default_values="1">
        <BooleanDomain name="bool" />
        <Documentation>A cell with a zero vector at a corner has no data (land, solid cells), as
        when the command line reads a file. Off: zeros flow (stagnation points of sampled
        analytic fields).</Documentation>
      </IntVectorProperty>
)";
}

void write_xml(std::ostream& out) {
  out << "<ServerManagerConfiguration>\n  <!-- Made by orthofront-paraview-properties from the "
         "option schemas: do not edit. -->\n  <ProxyGroup name=\"filters\">\n";
  for (const pv::PluginFilter& filter : pv::kPluginFilters) {
    const SurfaceKind kind = filter.kind;
    const KindOptions options(kind);
    const std::string help = orthofront::io::xml_escaped(filter.help);
    out << "    <SourceProxy name=\"" << filter.proxy_name << "\" class=\"" << filter.class_name
        << "\" label=\"" << filter.label << "\">\n";
    out << "      <Documentation short_help=\"" << help << "\" long_help=\"" << help << "\">"
        << help << "</Documentation>\n";
    write_input_properties(out);
    if (kind == SurfaceKind::streak)  // the frames, as the output's time steps
      out << "      <DoubleVectorProperty name=\"TimestepValues\" information_only=\"1\" "
             "repeatable=\"1\">\n        <TimeStepsInformationHelper />\n"
             "        <Documentation>The frames' times.</Documentation>\n"
             "      </DoubleVectorProperty>\n";
    std::vector<OptionGroup> groups;
    for (const OptionSpec& spec : options.set.specs()) {
      if (!pv::on_panel(spec)) continue;
      write_property(out, spec);
      bool seen = false;
      for (const OptionGroup g : groups) seen = seen || g == spec.group;
      if (!seen) groups.push_back(spec.group);
    }
    for (const OptionGroup g : groups) {
      out << "      <PropertyGroup label=\"" << orthofront::jobs::group_title(g) << "\">\n";
      for (const OptionSpec& spec : options.set.specs())
        if (pv::on_panel(spec) && spec.group == g)
          out << "        <Property name=\"" << pv::property_name(spec.name) << "\" />\n";
      out << "      </PropertyGroup>\n";
    }
    out << "      <Hints>\n        <ShowInMenu category=\"orthofront\" />\n      </Hints>\n"
        << "    </SourceProxy>\n";
  }
  out << "  </ProxyGroup>\n</ServerManagerConfiguration>\n";
}

const char* setter_type(const OptionSpec& spec) {
  switch (spec.type) {
    case OptionType::real: return "double";
    case OptionType::count: return "vtkIdType";
    case OptionType::text: return "const char*";
    default: return "int";
  }
}

void write_header(std::ostream& out, const pv::PluginFilter& filter) {
  const SurfaceKind kind = filter.kind;
  const KindOptions options(kind);
  const std::string cls = filter.class_name;
  out << "// Made by orthofront-paraview-properties from the option schema: do not edit.\n"
      << "#pragma once\n#include \"vtkOrthofrontSurfaceFilter.h\"\n\n"
      << "#include \"OrthofrontFiltersModule.h\"\n\n"
      << "/// " << filter.help << "\n"
      << "class ORTHOFRONTFILTERS_EXPORT " << cls << " : public vtkOrthofrontSurfaceFilter {\n"
      << " public:\n  static " << cls << "* New();\n  vtkTypeMacro(" << cls
      << ", vtkOrthofrontSurfaceFilter)\n\n";
  for (const OptionSpec& spec : options.set.specs()) {
    if (!pv::on_panel(spec)) continue;
    const std::string name = pv::property_name(spec.name);
    out << "  /// --" << spec.name << "\n  void Set" << name << "(" << setter_type(spec)
        << " value) { this->SetOptionValue(\"" << spec.name << "\", value";
    if (spec.type == OptionType::choice) {
      out << ", {";
      for (std::size_t i = 0; i < spec.choices.size(); ++i)
        out << (i ? ", " : "") << "\"" << spec.choices[i] << "\"";
      out << "}";
    }
    if (spec.type == OptionType::flag) out << ", true";
    out << "); }\n";
  }
  out << "\n protected:\n  " << cls << "() : vtkOrthofrontSurfaceFilter(\"" << to_string(kind)
      << "\") {}\n\n private:\n  " << cls << "(const " << cls << "&) = delete;\n  void operator=(const "
      << cls << "&) = delete;\n};\n";
}

// Written whole to a temporary name, then renamed: a build never sees half a file.
int write_file(const std::string& path, const std::string& text) {
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    if (!out) {
      std::cerr << "orthofront-paraview-properties: cannot write " << temporary << "\n";
      return 1;
    }
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    std::cerr << "orthofront-paraview-properties: cannot rename " << temporary << " to " << path
              << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  std::ostringstream text;
  if (args.size() == 2 && args[0] == "xml") {
    write_xml(text);
    return write_file(args[1], text.str());
  }
  if (args.size() == 3 && args[0] == "header") {
    const auto kind = orthofront::jobs::parse_surface_kind(args[1]);
    if (!kind) {
      std::cerr << "orthofront-paraview-properties: unknown kind '" << args[1] << "'\n";
      return 2;
    }
    for (const pv::PluginFilter& filter : pv::kPluginFilters)
      if (filter.kind == *kind) {
        write_header(text, filter);
        return write_file(args[2], text.str());
      }
    std::cerr << "orthofront-paraview-properties: the plugin has no filter for '" << args[1]
              << "'\n";
    return 2;
    return write_file(args[2], text.str());
  }
  std::cerr << "usage: orthofront-paraview-properties xml OUT.xml | header KIND OUT.h\n";
  return 2;
}
