#pragma once
/// How the option schemas become ParaView properties: the names, which options the panel shows,
/// and which take their default from the data. Shared by the property generator and the filters,
/// so the properties a filter reads are the ones the XML declares.
#include <algorithm>
#include <string>

#include "jobs/option_spelling.h"
#include "jobs/surface_kind.h"

namespace orthofront::paraview {

/// "flat-split" -> "Flat Split": the property's label, as messages name it
/// (jobs::option_label).
inline std::string property_label(const std::string& option) { return jobs::option_label(option); }

/// "flat-split" -> "FlatSplit": the property's name and, with "Set", its setter.
inline std::string property_name(const std::string& option) {
  std::string name = property_label(option);
  name.erase(std::remove(name.begin(), name.end(), ' '), name.end());
  return name;
}

/// Options whose default comes from the data or the machine (the grid's cell size, the memory
/// available): the panel shows 0 (or nothing) for "as the command line chooses it".
inline bool from_data(const jobs::OptionSpec& spec) {
  for (const char* name : {"edge", "max-vertices", "t0", "t1", "release", "frames"})
    if (spec.name == name) return true;
  return !spec.show_default;
}

/// What the command line takes when a from_data() option is not given.
inline std::string from_data_meaning(const jobs::OptionSpec& spec) {
  if (spec.name == "edge") return "the input's cell size";
  if (spec.name == "max-vertices") return "from the memory limit";
  if (spec.name == "time-budget") return "no time limit";
  if (spec.name == "t0") return "the input's first time";
  if (spec.name == "t1") return "the input's last time";
  if (spec.name == "release") return "over the input's whole time range";
  if (spec.name == "frames") return "every input time step after the release begins";
  if (spec.name == "vertex-budget") return "half the vertex cap";
  if (spec.name == "cache-budget") return "a quarter of the memory limit";
  if (spec.name == "memory") return "the memory available when the filter runs";
  return "as the command line chooses it";
}

/// All but the device (the plugin runs on the CPU), the command line's other streak routes and
/// its space-time output file.
inline bool on_panel(const jobs::OptionSpec& spec) {
  for (const char* name : {"route", "point", "spacetime-out"})
    if (spec.name == name) return false;
  return spec.name.rfind("device", 0) != 0;
}

/// The options on the panel's first page; the rest are advanced.
inline bool shown_by_default(const jobs::OptionSpec& spec) {
  for (const char* name : {"edge", "steps", "seed-count", "method", "t0", "t1", "release", "frames"})
    if (spec.name == name) return true;
  return false;
}

/// A kind's filter: its VTK class, server-manager proxy, menu label and help.
struct PluginFilter {
  jobs::SurfaceKind kind;
  const char* class_name;
  const char* proxy_name;
  const char* label;
  const char* help;
};

/// The kinds the compiled plugin has filters for.
inline constexpr PluginFilter kPluginFilters[] = {
    {jobs::SurfaceKind::stream, "vtkOrthofrontStreamSurface", "OrthofrontStreamSurface",
     "Orthofront Stream Surface",
     "A stream surface of a steady vector field from a seed line, its front kept orthogonal to "
     "the flow: flow-aligned, near-square quads (orthofront stream)."},
    {jobs::SurfaceKind::path, "vtkOrthofrontPathSurface", "OrthofrontPathSurface",
     "Orthofront Path Surface",
     "A path surface of a time-dependent field from a seed line: the surface its path lines "
     "sweep from T0 to T1, front kept orthogonal to the flow (orthofront path). The input's time "
     "steps are read one at a time."},
    {jobs::SurfaceKind::streak, "vtkOrthofrontStreakSurface", "OrthofrontStreakSurface",
     "Orthofront Streak Surface",
     "A streak surface of a time-dependent field from a seed line: dye released continuously, "
     "one output time step per frame (orthofront streak). The input's time steps are read one "
     "at a time."},
};

}  // namespace orthofront::paraview
