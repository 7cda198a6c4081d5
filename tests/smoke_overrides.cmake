# Per-case overrides that keep smoke runs short: GABION_SMOKE_SET_<case name>
# holds the extra arguments given to `gabion run` (a list of --set a.b=v).
