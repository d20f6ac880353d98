#pragma once
// A file compiled into an executable by tactus_embed (cmake/TactusEmbed.cmake): its name and bytes.
#include <string_view>
#include <vector>

namespace tactus {

struct EmbeddedFile {
  const char* name;
  std::string_view text;
};

}  // namespace tactus
