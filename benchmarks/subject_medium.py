"""The medium whose figures the benchmarks print and docs/ publishes: the round yarn of particles and
voids that was the default until the yarn of fibres in air replaced it (docs/fitting.md, "The default: a
red of fibres in air").  Kept so that every published figure stays reproducible by its command."""

SUBJECT_PRESET = "voided_red_cotton"
