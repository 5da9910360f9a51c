# SPDX-License-Identifier: Apache-2.0
# CAN flap: vcan0 down and up 1000 times under a streaming tacse3d; the stream resumes every time.
# shellcheck shell=sh
# vm-arch: aarch64
# vm-timeout: 3600
# vm-default: no
set -eu
. /tacse3/lib.sh

can_flap_scenario 1000
