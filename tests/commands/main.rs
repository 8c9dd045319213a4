//! Tests of the command line: the commands, charts (and the cameras they are seen through), the
//! bake stage, fault handling, the input fuzzer, the generated documentation tables and the HTML
//! report in a browser. One binary so the library is linked once.

#[path = "../support/mod.rs"]
mod support;

mod bake_stage;
mod camera;
mod chart;
mod cli;
mod docs_tables;
mod faults;
mod fuzz;
mod prt_refine;
mod report;
mod scale;
mod slow_bakes;
