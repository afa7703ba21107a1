// calstand import / export: moves runs in and out of a database as `calstand-import/1` folders
// (meta.json + samples.csv, ../shared/docs/error-model.md), e.g. data recorded by another
// station, or a run handed to another tool.
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "open_database.hpp"
#include "store/database.hpp"
#include "store/import_export.hpp"

namespace calstand::cli {
namespace {

struct ImportOptions {
  std::string dir;
  std::string db = "calstand.db";
  bool json = false;
};

struct ExportOptions {
  std::string db = "calstand.db";
  std::int64_t run = 0;
  std::string out;
  std::string device;
};

void run_import(const ImportOptions& o) {
  store::Database db(o.db);
  const store::ImportResult r = store::import_run(db, o.dir);
  if (o.json) {
    nlohmann::ordered_json j;
    j["run"] = r.run;
    j["steps"] = r.steps;
    j["samples"] = r.samples;
    std::cout << j.dump() << "\n";
  } else {
    std::cout << r.run << "\n";
  }
}

void run_export(const ExportOptions& o) {
  store::Database db = open_existing_database(o.db);
  store::export_run(db, o.run, o.out, {o.device});
}

}  // namespace

void register_import_export(CLI::App& app) {
  auto in = std::make_shared<ImportOptions>();
  CLI::App* imp =
      app.add_subcommand("import",
                         "Create a run from a calstand-import/1 folder (meta.json + samples.csv); "
                         "prints the run id");
  imp->add_option("dir", in->dir, "folder holding meta.json and samples.csv")->required();
  imp->add_option("--db", in->db, "database file (created when absent)")->capture_default_str();
  imp->add_flag("--json", in->json, R"(print {"run": ID, "steps": N, "samples": M})");
  imp->callback([in] { run_import(*in); });

  auto out = std::make_shared<ExportOptions>();
  CLI::App* exp = app.add_subcommand(
      "export", "Write a run as a calstand-import/1 folder (meta.json + samples.csv)");
  exp->add_option("--db", out->db, "database file")->capture_default_str();
  exp->add_option("--run", out->run, "run id (see calstand runs)")->required();
  exp->add_option("--out", out->out, "output folder (created; its two files are overwritten)")
      ->required();
  exp->add_option("--device", out->device, "IMU to export when the run has several");
  exp->callback([out] { run_export(*out); });
}

}  // namespace calstand::cli
