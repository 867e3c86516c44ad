// Parsing an enum from the name its Name() function gives: one loop and one
// error message for every option an enum stands for (merge rule, provider,
// model role, ...). Name() stays a switch, so the compiler flags a value
// without a name.
#pragma once

#include <initializer_list>
#include <string>
#include <string_view>

#include "semrec/core/error.h"

namespace semrec {

/// The value of `values` whose `name_of(value)` is `text`. Throws
/// InvalidArgument "<what> must be one of a, b, c, not '<text>'".
template <typename Enum, typename NameOf>
Enum ParseEnumName(const std::string& text, std::initializer_list<Enum> values,
                   NameOf name_of, std::string_view what) {
  std::string names;
  for (const Enum value : values) {
    const std::string_view name = name_of(value);
    if (text == name) return value;
    if (!names.empty()) names += ", ";
    names += name;
  }
  throw InvalidArgument(std::string(what) + " must be one of " + names +
                        ", not '" + text + "'");
}

}  // namespace semrec
