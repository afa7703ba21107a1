// Reading a procedure: JSON text -> schema -> the rules that need no parameter values.
#include "procedures/procedure.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/schemas.hpp"
#include "procedures/library.hpp"
#include "static_checks.hpp"

namespace calstand::procedures {
namespace {

// InputError writes "where: why"; the file goes in front of every line but the first.
std::string violation_lines(const std::string& file_name, const std::vector<Violation>& vs) {
  if (vs.empty()) return "is not a valid procedure";
  std::string text;
  for (std::size_t i = 0; i < vs.size(); ++i) {
    if (i > 0) text += "\n" + (file_name.empty() ? std::string() : file_name + ": ");
    text += (vs[i].path.empty() ? std::string() : vs[i].path + ": ") + vs[i].message;
  }
  return text;
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::InputError(path, "cannot open the procedure file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw core::InputError(path, "cannot read the procedure file");
  return text.str();
}

}  // namespace

ProcedureError::ProcedureError(const std::string& file_name, std::vector<Violation> violations)
    : core::InputError(file_name, violation_lines(file_name, violations)),
      violations_(std::move(violations)) {}

Procedure parse_procedure(std::string_view text, const std::string& file_name) {
  Procedure p;
  p.doc = core::parse_json_text(text, file_name);
  auto violations = core::schema("procedure.schema.json").validate(p.doc);
  if (!violations.empty()) throw ProcedureError(file_name, std::move(violations));

  p.parameter_specs = detail::read_parameter_specs(p.doc, violations);
  detail::check_steps(p.doc, p.parameter_specs, violations);
  if (!violations.empty()) throw ProcedureError(file_name, std::move(violations));

  p.name = p.doc["name"].get<std::string>();
  p.description = p.doc.value("description", "");
  p.file_name = file_name;
  p.source_text = std::string(text);
  for (const auto& [name, spec] : p.parameter_specs) p.parameters[name] = spec.default_value;
  return p;
}

Procedure load_procedure(const std::string& name_or_path) {
  if (const auto text = library_text(name_or_path)) {
    return parse_procedure(*text, "library/" + name_or_path + ".json");
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(name_or_path, ec)) {
    std::string names;
    for (const auto& n : library_names()) names += (names.empty() ? "" : ", ") + n;
    throw core::InputError(name_or_path,
                           "no such procedure file, nor a library procedure (" + names + ")");
  }
  return parse_procedure(read_text_file(name_or_path), name_or_path);
}

}  // namespace calstand::procedures
