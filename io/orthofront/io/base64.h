#pragma once
/// Base64 as VTK XML uses it for inline binary arrays (internal to the mesh codecs).
#include <string>
#include <string_view>

namespace orthofront::io::detail {

/// Encodes `bytes` as one line of standard base64 with '=' padding.
std::string base64_encode(std::string_view bytes);
/// The same into `out` (its storage reused).
void base64_encode(std::string_view bytes, std::string& out);

/// Decodes `text` into `bytes`, skipping whitespace. Padding may also occur inside the text, as
/// writers that encode a header and its data separately produce it. Returns false on a character
/// outside the base64 alphabet or a misplaced '='.
bool base64_decode(std::string_view text, std::string& bytes);

}  // namespace orthofront::io::detail
