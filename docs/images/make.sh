#!/usr/bin/env bash
# Regenerates the README's pictures with samara's own commands (and, for the beam frames and
# the right-angle cantilever against its published curves, two matplotlib scripts).
# Run from anywhere: docs/images/make.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --quiet
samara=target/release/samara
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
$samara run examples/pendulum.toml --out "$tmp/pendulum" --quiet > /dev/null
$samara plot "$tmp/pendulum/swing.nc" position:bob:x position:bob:z joint_force:pivot:y \
    kinetic_energy potential_energy --out docs/images/pendulum.png
$samara run examples/double_pendulum.toml --out "$tmp/double" --quiet > /dev/null
$samara plot "$tmp/double/swing.nc" position:bob2:x position:bob2:z kinetic_energy potential_energy \
    --out docs/images/double_pendulum.png
$samara run examples/heavy_top.toml --out "$tmp/top" --quiet > /dev/null
$samara plot "$tmp/top/precession.nc" orientation:top:w orientation:top:x orientation:top:y orientation:top:z \
    joint_force:pivot:x joint_force:pivot:y joint_force:pivot:z --out docs/images/heavy_top.png
$samara run examples/landing_gear.toml --out "$tmp/gear" --quiet > /dev/null
$samara plot "$tmp/gear/retract.nc" joint_coordinate:trunnion.theta3 joint_coordinate:actuator.d3 \
    joint_coordinate:oleo.d3 joint_coordinate_force:actuator.d3 joint_coordinate_force:oleo.d3 \
    --out docs/images/landing_gear.png
$samara run examples/landing_gear_drop.toml --out "$tmp/gear_drop" --quiet > /dev/null
$samara plot "$tmp/gear_drop/drop_and_retract.nc" joint_coordinate:oleo.d3 \
    element_output:shock_strut.actuator.force element_output:tire.normal_force \
    element_output:tire.longitudinal_force element_output:tire.brake_torque \
    element_state:tire.slip_ratio joint_coordinate:trunnion.theta3 \
    --out docs/images/landing_gear_drop.png
$samara run examples/four_bar.toml --out "$tmp/four_bar" --quiet > /dev/null
$samara plot "$tmp/four_bar/turn.nc" joint_coordinate:crank_pivot.theta3 joint_coordinate:rocker_pivot.theta3 \
    joint_coordinate_force:crank_pivot.theta3 --out docs/images/four_bar.png
$samara run examples/adaptive_kick.toml --out "$tmp/kick" --quiet > /dev/null
$samara plot "$tmp/kick/kick.nc" step_size position:mass:x --out docs/images/adaptive_kick.png
$samara run examples/verification/right_angle_cantilever.toml --out "$tmp/rac" --quiet > /dev/null
python3 docs/images/right_angle_cantilever.py "$tmp/rac/dynamic.nc" docs/images/right_angle_cantilever.png
python3 docs/images/beam_frames.py
$samara section examples/sections/airfoil.section.toml --out "$tmp/section" --plot > /dev/null 2>&1
cp "$tmp/section/airfoil.png" docs/images/section_airfoil.png
$samara run examples/verification/rotating_beam_campbell.toml --out "$tmp/campbell" --quiet > /dev/null
$samara plot "$tmp/campbell/campbell.nc" campbell --out docs/images/rotating_beam_campbell.png
$samara run examples/rotor/nrel5mw_rotor.toml --out "$tmp/nrel5mw" --quiet > /dev/null
$samara plot "$tmp/nrel5mw/spin.nc" span blade1 alpha cl axial_induction normal_load tangential_load \
    --out docs/images/nrel5mw_span.png
cargo run --release --quiet -p samara --example nrel5mw_curves > "$tmp/curves.csv"
python3 docs/images/nrel5mw_curves.py "$tmp/curves.csv" docs/images/nrel5mw_curves.png
$samara run examples/rotor/hingeless_blade_campbell.toml --out "$tmp/hingeless" --quiet > /dev/null
$samara plot "$tmp/hingeless/campbell.nc" campbell --out docs/images/hingeless_blade_campbell.png
cargo run --release --quiet -p samara --example dynamic_stall_loops -- docs/images/dynamic_stall_loops.svg
