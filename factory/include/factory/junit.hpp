#pragma once
// An acceptance as JUnit XML, for the CI pipelines that rehearse procedures on the simulator:
// one <testsuite> per unit, one <testcase> per check.

#include <string>

#include "factory/accept_run.hpp"

namespace calstand::analysis {

/// The outcome as a JUnit XML document (the de-facto schema Jenkins, GitLab and GitHub read):
/// <testsuites> holding one <testsuite> per unit, named `<device>` or `<device> <serial>`, with
/// <properties> (device, serial, calibration, run, verdict, spec, spec_sha256, k,
/// decision_rule); one <testcase> per check (name: the check, classname:
/// `calstand.accept.<device>`). A failed check holds <failure type="fail">, an indeterminate
/// one <failure type="indeterminate"> (a CI job must not go green on a unit that is not shown
/// to pass; `calstand accept` exits 1 for it too); every test case holds its value, sigma,
/// limit, verdict and reason in <system-out>. UTF-8, markup characters escaped.
std::string junit_xml(const AcceptanceOutcome& outcome);

}  // namespace calstand::analysis
