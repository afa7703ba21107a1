// `calstand certificate`: a unit's calibration certificate as HTML, or PDF (headless Chromium).
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/file_output.hpp"
#include "factory/certificate.hpp"
#include "open_database.hpp"
#include "render/html_to_pdf.hpp"

namespace calstand::cli {
namespace {

struct CertificateOptions {
  std::string db;
  std::int64_t run = 0;
  std::string device;
  std::int64_t calibration = 0;
  std::string out;
};

void run_certificate(const CertificateOptions& opt) {
  store::Database db = open_existing_database(opt.db);
  if (opt.calibration == 0 && opt.run == 0) {
    throw core::InputError("--run", "give the run (and --device) or --calibration");
  }
  const std::int64_t id = opt.calibration != 0
                              ? opt.calibration
                              : analysis::calibration_of_unit(db, opt.run, opt.device);
  const analysis::CertificateData data = analysis::certificate_data(db, id);
  const std::string html = analysis::certificate_html(data);
  if (std::filesystem::path(opt.out).extension() == ".pdf") {
    analysis::html_to_pdf(html, opt.out);
  } else {
    core::write_file_whole(opt.out, html);
  }
  fmt::print("certificate {} of unit {} ({}) written to {}\n", data.number,
             data.serial.empty() ? "(no serial)" : data.serial, data.device, opt.out);
}

}  // namespace

void register_certificate(CLI::App& app) {
  auto opt = std::make_shared<CertificateOptions>();
  auto* cmd = app.add_subcommand(
      "certificate",
      "A unit's calibration certificate (HTML, or PDF when --out ends in .pdf: headless "
      "Chromium's print), one A4 page");
  cmd->add_option("--db", opt->db, "Database file")->required();
  cmd->add_option("--run", opt->run, "Run whose newest record of the unit is certified");
  cmd->add_option("--device", opt->device, "The unit's IMU slot (needed when several)");
  cmd->add_option("--calibration", opt->calibration, "Certify this calibration record instead");
  cmd->add_option("--out", opt->out, "Output file, .html or .pdf")->required();
  cmd->callback([opt] { run_certificate(*opt); });
}

}  // namespace calstand::cli
