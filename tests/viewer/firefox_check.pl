#!/usr/bin/perl
# SPDX-License-Identifier: Apache-2.0
# The replay view in headless Firefox, driven over Marionette by Debian's
# libfirefox-marionette-perl (Debian has no geckodriver): the page opens on frame 0 with every
# plot, the scrubber moves the frame shown (readouts, image, 3D view with the truth), and a
# screenshot is saved. Run by firefox_test.py; exit 0 when every check holds, 1 naming the first
# that fails.
# Usage: firefox_check.pl URL SCREENSHOT
use strict;
use warnings;
use Firefox::Marionette();
use Time::HiRes qw(sleep time);

my ($url, $screenshot) = @ARGV;
die "usage: firefox_check.pl URL SCREENSHOT\n" unless defined $screenshot;

my $firefox = Firefox::Marionette->new(visible => 0, width => 1500, height => 1500);
my $failed = 0;

sub js { return $firefox->script($_[0], args => [ @_[1 .. $#_] ]); }

sub check {
  my ($ok, $what) = @_;
  print(($ok ? "ok   " : "FAIL ") . "$what\n");
  $failed = 1 unless $ok;
  return $ok;
}

sub wait_for {
  my ($what, $fn, $timeout_s) = @_;
  my $end = time + $timeout_s;
  while (time < $end) {
    return 1 if $fn->();
    sleep 0.1;
  }
  return check(0, "timed out after $timeout_s s waiting for $what");
}

# Standard deviation of the left pad canvas's luma (the image with its overlays).
my $canvas_sd = <<'JS';
const c = document.querySelector('#pad-left canvas');
const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
let s = 0, s2 = 0;
for (let i = 0; i < d.length; i += 4) {
  const y = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2];
  s += y; s2 += y * y;
}
const n = d.length / 4, m = s / n;
return Math.sqrt(Math.max(0, s2 / n - m * m));
JS

my $shown = 'return window.tacse3 ? window.tacse3.recording().shown : -1';
$firefox->go($url);
if (wait_for('frame 0', sub { js($shown) == 0 }, 30)) {
  check(js('return window.tacse3.plots()') == 6, 'every plot was created');
  check(js("return document.getElementById('plots-missing').hidden"), 'uPlot is bundled');
  check(js($canvas_sd) > 5, 'the left pad shows an image');
  my $image0 = js("return document.querySelector('#pad-left canvas').toDataURL()");
  js("const f = document.getElementById('frame'); f.value = arguments[0];"
     . "f.dispatchEvent(new Event('input'));", 120);
  if (wait_for('frame 120', sub { js($shown) == 120 }, 15)) {
    check(js("return document.getElementById('cycle').textContent") eq '121',
          'the cycle readout follows the scrubber');
    check(js("return document.querySelector('#pad-left canvas').toDataURL()") ne $image0,
          'the left pad image follows the scrubber');
    my $moved = js('const p = window.tacse3.pose3d(); '
                   . 'return Math.hypot(p.object.axes[0][0] - p.g.axes[0][0], '
                   . 'p.object.axes[0][1] - p.g.axes[0][1]);');
    check($moved > 0.5, sprintf('the 3D view turned the object (x tip %.2f px from G\'s)', $moved));
    check(!js("return document.getElementById('truth-caption').hidden"), 'the truth is drawn');
  }
}
open(my $fh, '>', $screenshot) or die "$screenshot: $!\n";
binmode $fh;
print $fh $firefox->selfie(raw => 1);
close $fh;
$firefox->quit;
exit $failed;
