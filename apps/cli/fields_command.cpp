#include <iostream>

#include "cli/commands.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/unsteady.h"

namespace orthofront::cli {

void add_fields_command(CLI::App& app) {
  CLI::App* c = app.add_subcommand("fields", "List the analytic fields, parameters and domains");
  c->callback([]() {
    for (const AnalyticFieldInfo& f : analytic_fields()) {
      std::cout << f.name << "\n  " << f.formula << "\n  domain: " << f.domain << "\n";
      for (const FieldParameter& p : f.parameters)
        std::cout << "  " << p.name << " = " << p.default_value << "  " << p.help << "\n";
    }
    std::cout << "\nUnsteady fields (for `orthofront path`):\n";
    for (const AnalyticFieldInfo& f : unsteady_fields()) {
      std::cout << f.name << "\n  " << f.formula << "\n  domain: " << f.domain << "\n";
      for (const FieldParameter& p : f.parameters)
        std::cout << "  " << p.name << " = " << p.default_value << "  " << p.help << "\n";
    }
    std::cout << "Parameters are given as NAME:key=value,key=value "
                 "(e.g. lorenz:rho=28,reverse=1).\n";
  });
}

}  // namespace orthofront::cli
