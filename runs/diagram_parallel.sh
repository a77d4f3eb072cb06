#!/bin/bash
# The shape diagram spread over the cores of one machine (or over hosts with --sshlogin)
# with GNU parallel: one process per case, then one merge. Same CSV as a single
# `vesicle diagram runs/diagram.json --out out/diagram`.
set -euo pipefail
N=$(vesicle diagram runs/diagram.json --list | tail -1 | cut -d' ' -f1)
seq 0 $((N - 1)) | parallel --bar vesicle diagram runs/diagram.json --out out/diagram --case {}
vesicle diagram runs/diagram.json --out out/diagram --merge
