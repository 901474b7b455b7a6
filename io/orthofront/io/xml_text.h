#pragma once
/// Text put into XML written by the project (.vtp, .pvd, .xmf): the five characters XML reserves
/// in attribute values and content, escaped.
#include <string>
#include <string_view>

namespace orthofront::io {

inline std::string xml_escaped(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace orthofront::io
