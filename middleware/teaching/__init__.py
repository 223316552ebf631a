"""Teaching: video lessons with cue tracks, tours (fully guided and live classes), personal practice robots,
the declarative command form they share, and the demo content `telelab up` seeds."""
