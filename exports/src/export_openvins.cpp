// OpenVINS' kalibr_imu_chain.yaml: the scale-misalignment intrinsics and the noise densities
// (docs/exports.md, "OpenVINS / Kalibr").
//
// OpenVINS (ov_msckf Propagator, docs/propagation-analytical.dox) corrects a sample as
//   a_hat = R_ACCtoIMU Da (a_m - b_a),   w_hat = R_GYROtoIMU Dw (w_m - b_g - Tg a_hat)
// with Dw = Tw^-1, Da = Ta^-1, R_*toIMU = R_IMUto*^T, rad/s and m/s^2: Tw and Ta map the truth
// (in the sensor's frame) to the measurement. Its "kalibr" model keeps only the lower triangle
// of Dw and Da (VioManagerOptions::print_and_load_state), so calstand's full matrix
// K = I + S + M is split as K = L Q (L lower triangular, Q a rotation): T = L, R_IMUto* = Q.
// Both rotations are read from the file in either model, so the IMU frame stays the record's
// body frame.
#include <fmt/format.h>

#include <string>

#include "analysis/noise_json.hpp"
#include "core/error.hpp"
#include "export_formats.hpp"
#include "export_terms.hpp"
#include "noise/kalibr.hpp"
#include "tablefree/triad_model.hpp"

namespace calstand::analysis::exporting {
namespace {

std::string matrix_yaml(const char* key, const Eigen::Matrix3d& m) {
  // Rows as flow sequences: ov_core's YamlParser reads node[row][col].
  std::string out = fmt::format("  {}:\n", key);
  for (int r = 0; r < 3; ++r) {
    out += fmt::format("    - [{:.15g}, {:.15g}, {:.15g}]\n", m(r, 0) == 0.0 ? 0.0 : m(r, 0),
                       m(r, 1) == 0.0 ? 0.0 : m(r, 1), m(r, 2) == 0.0 ? 0.0 : m(r, 2));
  }
  return out;
}

solver::LowerTriangularFrame split(const Eigen::Matrix3d& k, const char* sensor) {
  try {
    return solver::lower_triangular_frame(k);
  } catch (const core::InputError& e) {
    throw core::InputError(std::string(sensor) + "_scale, " + sensor + "_misalignment", e.what());
  }
}

}  // namespace

ExportResult export_openvins(const solver::Calibration& calibration, const ExportOptions& options) {
  const RecordTerms t = record_terms(calibration);
  ExportResult out;

  // The noise densities as `calstand noise --kalibr` writes them (noise/kalibr.cpp), from the
  // figures the record keeps: its identified models' where it has them, else the Allan line's.
  const nlohmann::json record_noise = calibration.record.value("noise", nlohmann::json());
  const std::optional<solver::RunNoise> noise = calibration_noise_terms(record_noise);
  const auto models = calibration_noise_models(record_noise);
  solver::KalibrImu imu;
  std::vector<std::string> unresolved;
  if (noise && models) {
    imu = solver::kalibr_from_noise_models(*noise, *models, options.rostopic, &unresolved);
  } else if (noise) {
    imu = solver::kalibr_from_run_noise(*noise, options.rostopic, &unresolved);
  } else {
    imu.rostopic = options.rostopic;
    out.warnings.push_back(
        "the record has no noise figures (its run had no static capture of 600 s): "
        "imu0's noise densities and random walks are written as 0, which OpenVINS cannot use; "
        "measure them (calstand noise --kalibr) and fill them in");
  }
  for (const std::string& field : unresolved) {
    out.warnings.push_back(fmt::format(
        "{}: not resolved on every axis by the record's static capture; written as the largest "
        "resolved axis or 0",
        field));
  }
  imu.update_rate_hz = options.update_rate_hz.value_or(noise ? noise->sample_rate_hz : 0.0);
  if (!(imu.update_rate_hz > 0.0)) {
    throw core::InputError("--update-rate",
                           "the record holds no sample rate (no noise figures, or written before "
                           "they kept one): give the IMU's update rate in Hz");
  }
  // imu.yaml's lines, one level down under imu0.
  const std::string flat = solver::kalibr_yaml(imu);
  std::string noise_block;
  for (std::string_view rest = flat; !rest.empty();) {
    const auto end = rest.find('\n');
    noise_block += "  " + std::string(rest.substr(0, end)) + "\n";
    rest = end == std::string_view::npos ? std::string_view() : rest.substr(end + 1);
  }

  const solver::LowerTriangularFrame gyro = split(t.gyro.scale_matrix(), "gyro");
  const solver::LowerTriangularFrame accel = split(t.accel.scale_matrix(), "accel");
  // calstand: G (f / g0) in deg/s; OpenVINS: Tg a_hat in rad/s with a_hat in m/s^2.
  const Eigen::Matrix3d tg = t.g_sensitivity * (kRadPerDeg / kStandardGravity);

  out.text = "%YAML:1.0\n";  // OpenCV's FileStorage, which OpenVINS reads this with, wants it
  out.text +=
      "# OpenVINS IMU configuration (kalibr_imu_chain.yaml) from a calstand calibration record.\n"
      "# " +
      record_identity(calibration) +
      "\n"
      "# Conventions: calstand docs/exports.md. Model \"kalibr\": a_hat = R_IMUtoACC^T Ta^-1 "
      "(a_m - b_a),\n"
      "# w_hat = R_IMUtoGYRO^T Tw^-1 (w_m - b_g - Tg a_hat); Tw, Ta lower triangular; the IMU "
      "frame is\n"
      "# the record's body frame. The biases are not in this file: OpenVINS estimates them.\n"
      "imu0:\n";
  out.text += noise_block;
  out.text += "  model: \"kalibr\"\n";
  out.text += matrix_yaml("Tw", gyro.L);
  out.text += matrix_yaml("R_IMUtoGYRO", gyro.Q);
  out.text += matrix_yaml("Ta", accel.L);
  out.text += matrix_yaml("R_IMUtoACC", accel.Q);
  out.text += matrix_yaml("Tg", tg);

  std::vector<std::string> biases;
  for (const auto& p : t.parameters) {
    const std::string base = term_base_name(p);
    if (base == "gyro_bias" || base == "accel_bias") biases.push_back(p.name);
  }
  if (!biases.empty()) {
    out.warnings.push_back(fmt::format(
        "{} are not part of kalibr_imu_chain.yaml: OpenVINS estimates the biases online from "
        "zero (correct the samples with them, or expect the filter to converge to them)",
        join_parameter_names(biases)));
  }
  const auto kept = [](std::string_view term) {
    return term == "gyro_bias" || term == "accel_bias" || term == "gyro_scale" ||
           term == "accel_scale" || term == "gyro_misalignment" || term == "accel_misalignment" ||
           term == "gyro_g_sensitivity";
  };
  if (auto w = left_out_warning(t, kept, "OpenVINS")) out.warnings.push_back(*w);
  if (auto w = undetermined_warning(calibration)) out.warnings.push_back(*w);
  return out;
}

}  // namespace calstand::analysis::exporting
