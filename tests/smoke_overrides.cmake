# Per-case overrides that keep smoke runs short: GABION_SMOKE_SET_<case name>
# holds the extra arguments given to `gabion run` (a list of --set a.b=v).
# fit.micro resumes from OUTDIR/evaluations.jsonl by default; a smoke run starts afresh.
set(GABION_SMOKE_SET_fit_micro_wall --set resume=false)
