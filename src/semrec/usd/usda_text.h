// Text helpers shared by the USDA layer writers (internal to usd/).
#pragma once

#include <string>
#include <vector>

#include "semrec/usd/usda_writer.h"

namespace semrec::usd::detail {

/// A USDA string literal: quotes and backslashes escaped, control characters
/// dropped.
std::string Quote(const std::string& s);
/// Shortest text that reads back to the same float.
std::string Num(float x);
/// `#usda 1.0` and the layer metadata (defaultPrim, metersPerUnit, upAxis,
/// time codes when set, customLayerData), with `extra` metadata lines.
std::string Header(const StageOptions& options, const std::string& extra);
/// A colour as a USD color3f tuple.
std::string Color3(const std::array<uint8_t, 3>& c);
/// The semantics labels of a prim, both conventions (see usda_writer.h).
std::string SemanticsAttributes(const std::string& label,
                                const std::string& indent);

/// The `Objects` / `People` scopes (indented for /World).
std::string ObjectsScopeText(const std::vector<MeshPrim>& meshes);
std::string PeopleScopeText(const std::vector<PersonTrack>& people,
                            const StageOptions& options);

}  // namespace semrec::usd::detail
