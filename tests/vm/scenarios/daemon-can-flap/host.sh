#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
exec bash "$TACSE3_REPO/tests/vm/lib/flapcheck.sh" "$TACSE3_VM_LOGDIR"
