#pragma once
/// The subcommands of the `orthofront` program and (add_bench_*) of `orthofront-bench`. Each
/// registers itself on the app; its callback throws orthofront::Error on bad input (run_app turns
/// that into a message and exit code 2).
#include <CLI/CLI.hpp>

namespace orthofront::cli {

void add_stream_command(CLI::App& app);
void add_fields_command(CLI::App& app);
void add_demo_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_path_command(CLI::App& app);
void add_streak_command(CLI::App& app);
void add_bench_path_command(CLI::App& app);
void add_bench_streak_command(CLI::App& app);
void add_generate_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_convert_command(CLI::App& app);
void add_bench_grid_command(CLI::App& app);
void add_bench_gpu_command(CLI::App& app);
void add_bench_front_command(CLI::App& app);
void add_bench_gpu_streak_command(CLI::App& app);
void add_batch_command(CLI::App& app);
void add_bench_batch_command(CLI::App& app);

}  // namespace orthofront::cli
