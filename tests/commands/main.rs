//! Tests of the command line: the commands, charts, the bake stage, fault handling, the input
//! fuzzer and the generated documentation tables. One binary so the library is linked once.

#[path = "../support/mod.rs"]
mod support;

mod bake_stage;
mod chart;
mod cli;
mod docs_tables;
mod faults;
mod fuzz;
