#include "store/derived_run.hpp"

#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>

#include "sql_util.hpp"
#include "step_writer.hpp"
#include "store/run_store.hpp"
#include "store/stamp.hpp"

namespace calstand::store {

std::int64_t write_derived_run(Database& db, const DerivedRun& derived) {
  RunStore runs(db);
  const RunRecord source = runs.load_run(derived.source_run);  // InputError when unknown
  return detail::guarded("write derived run", [&] {
    SQLite::Transaction tx(db.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    SQLite::Statement st(db.sql(),
                         "INSERT INTO runs (station_id, procedure_name, procedure_text, "
                         "procedure_sha256, parameters, station_snapshot, status, created_utc, "
                         "started_clock_s, ended_clock_s) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    if (source.station_id) {
      st.bind(1, *source.station_id);
    } else {
      st.bind(1);
    }
    st.bind(2, derived.procedure_name);
    st.bind(3, source.procedure_text);
    st.bind(4, source.procedure_sha256);
    nlohmann::json parameters = derived.parameters;
    parameters["source_run"] = derived.source_run;
    st.bind(5, parameters.dump());
    st.bind(6, source.station_snapshot.dump());
    st.bind(7, derived.status);
    st.bind(8, utc_now_iso8601());
    if (source.started_clock_s)
      st.bind(9, *source.started_clock_s);
    else
      st.bind(9);
    if (source.ended_clock_s)
      st.bind(10, *source.ended_clock_s);
    else
      st.bind(10);
    st.exec();
    const std::int64_t run = db.sql().getLastInsertRowid();
    detail::StepWriter writer(db.sql());
    for (const StepData& s : derived.steps) {
      if (s.samples.empty()) continue;
      detail::StepRow row;
      row.index = s.step.index;
      row.kind = s.step.kind.empty() ? "capture" : s.step.kind;
      row.label = s.step.label;
      row.commanded = s.step.commanded.is_null() ? nlohmann::json::object() : s.step.commanded;
      row.origin = s.step.origin;
      row.first_s = s.samples.front().receive_time_s;
      row.last_s = s.samples.back().receive_time_s;
      writer.write(run, row, derived.device, s.samples, s.table);
    }
    tx.commit();
    return run;
  });
}

}  // namespace calstand::store
