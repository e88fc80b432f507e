"""The ``robust`` tracker's occlusion logic: tracking / occluded / lost, read from the response.

Third link of the ``robust`` chain (before ``robust_motion``, which it tells whether to update
or coast, as S0's ``occlusion`` runs before ``kalman``). Every decision follows the correlation
filter's own response (``robust_search``), not a hand-set similarity:

- **Occluded** when the response's peak-to-sidelobe ratio falls below ``hidden_psr`` (Bolme et
  al., MOSSE, CVPR 2010, find PSR 20-60 while tracking and below 7 under occlusion or failure).
  The box stays on the response's peak (``coast``: it follows the motion model's prediction
  instead, S0 sec. 3, which suits a fixed camera but lowered the mean AUC on hand-held and
  panning footage); with ``learn_occluded`` the models still learn there when the colours
  agree (below). With ``coast_unseen``, an occluded frame whose colours at the peak fail the
  ``doubtful_colour`` check is one where neither learner sees the target: the box reported
  there is ``robust_motion``'s constant-velocity extrapolation from the last frame that saw
  it (unless that box is mostly outside the frame: then the peak's box, which this stage
  found in view), while the search, the models and the filter's own measurement stay at the
  peak as before (only the report changes). A target passing behind a plain occluder was reported
  on the occluder's edge until it came out (generated `slab`, seeds 100-111: mean IoU 0.731
  -> 0.862; `occlusion` and `cover` 0.72-0.94 -> 0.82-0.99), at a cost where a hand-held
  target's colours fail the check while the filter still has it (DragonBaby; real sequences
  -0.001 on both sets; benchmarks/RESULTS.md section 8, sixteenth round). Once the target has
  been hidden for more than ``lost_after`` frames, or at once when the box is mostly outside
  the frame, the state is **lost**: no box is claimed, and with
  ``redetect`` the next frames search a ring of regions around the motion model's last
  position with the same filter, a ring farther a frame (``ctx.search_growth``,
  :class:`vtrack.stages.robust_model.RobustModel`). Both count the frames elapsed, not the
  frames given (``ctx.clock``, :class:`vtrack.clock.FrameClock`: the frame numbers, or the
  timestamps where they say otherwise): a camera that delivers every other frame loses a
  hidden target after the same second as one that delivers all, and searches as far by then
  (before, a second later, its rings growing half as fast).
- **Doubtful**: a sharp peak below ``hidden_peak`` of its mean over the frames so far (Wang et
  al., LMCF, CVPR 2017: beta_2 = 0.45; a background texture can give a sharp peak, not a strong
  one) is called occluded too, but followed and learnt like a tracking frame, and it is no step
  towards lost: freezing the model there lowered the check sequences' mean AUC (0.606 ->
  0.546); as a label only it raised the share of missed frames flagged from 19% to 53%. With
  ``doubtful_colour``, a doubtful frame is learnt only when the other learner agrees: the
  colour response at the peak is at least that share of its mean so far (Staple's premise,
  two complementary learners; the share is LMCF's beta_1 = 0.7). A target passing behind a
  plain occluder gives doubtful peaks on the occluder's edge, whose colours are not the
  target's: learnt, the edge became the target (generated `slab` and `occlusion` scenes).
  A peak whose box lies mostly outside the frame is no sight of the target (it is leaving
  the view) and counts as hidden, so the box mostly outside makes it lost at once: followed
  as doubtful, a target out of view stayed occluded on weak peaks of the border it left by
  (generated `exit_return`: out-of-view frames called lost 184 -> 229 of 269 on seeds
  100-111; real sequences even, benchmarks/RESULTS.md section 8, thirteenth round), and a
  strong peak on the replicated border past the frame's edge was called tracking with the
  box wholly outside (a box given as the whole frame; every box on the 28 sequences from the
  given box, on the 14 outside them and on the hard scenes unchanged). "Mostly outside" is
  measured against the first box: less than half of its area inside the frame, or, for a
  first box partly outside (a target entering the view), less than half of the share of it
  that was inside then (such a box was lost on the first frame after it, whatever the
  response, and the target was never taken back as it came into view).
  The size is not measured on a doubtful frame, as on a hidden one (fDSST's scale samples
  there show the occluder too): a target passing slowly behind a plain occluder grew its box
  by a quarter on the occluder's edge and then followed the edge (generated `slab`, seeds
  100-111: 0.824 -> 0.843; beyond its declared looks, seeds 200-203, 0.64-0.73 -> 0.66-0.82;
  13 starts a sequence, tune 0.550 -> 0.543, check 0.551 -> 0.555; 14 real sequences outside
  the data 0.705 -> 0.709; benchmarks/RESULTS.md section 8, twentieth round).
- A hidden or lost target is taken back only on a response LMCF would call confident: sharp
  (PSR at least ``hidden_psr``), strong (its peak at least ``hidden_peak`` of its mean so far,
  LMCF's beta_2) and with an APCE of at least ``retake_apce`` of its mean so far (LMCF's
  beta_1 = 0.7). A sharp peak alone took background texture and occluder edges for the target,
  which was then learnt; with the peak test only, a target out of view was "found" on
  background (unseen seeds of the scenes, mean IoU: exit_return 0.48 -> 0.91, leave_return
  0.71 -> 0.89; of the check sequences' tracking frames 8.0% -> 4.4% miss the target), at a
  cost on the tune sequences (five starts each, 0.522 -> 0.512: returns after a change of
  appearance are taken back later; benchmarks/RESULTS.md section 8). With ``retake_colour``
  the colour learner must agree too (the colour response at the peak passes the
  ``doubtful_colour`` check, as for learning a doubtful frame): a pale target out of view was
  taken back on background whose texture the filter matched, its colours 0.13 of the
  target's (generated `exit_return` with saturation 30-170: seed 200 0.19 -> 0.93; real
  sequences: check ten unchanged, tune -0.001 from 13 starts; seventeenth round).
- **Redetection on colour** (``redetect_on_colour``): a frame whose colour response at the
  peak fails the ``doubtful_colour`` check says the target is not where the filter peaks (a
  target that moved more than its own size left the region, and the filter, which learnt the
  static background around it as context, still peaks sharply there). The next frame also
  searches where the merged response peaks over the whole frame (``robust_model``'s
  ``filter_redetect`` region); that far candidate competes only with a filter peak at least
  its mean so far (``robust_search``). The randomised ``fast`` scene 0.05 -> 0.56 on unseen
  seeds; real sequences even within noise (13 starts: tune 0.560 -> 0.557, check 0.534 ->
  0.531; benchmarks/RESULTS.md section 8, ninth round). A frame whose target that search found
  far away is followed by the same search (a target that fast may be as far again): `fast`
  0.56 -> 0.92 on seeds 100-111, 0.60 -> 0.89 at 1.6-2.0 widths a frame; every real
  sequence's track identical, from the given box and from 13 starts (tenth round).
- **Model update**: the filter, colour histograms and scale filter learn on every tracking (and
  doubtful) frame at their rates (Staple), never while lost. An occluded frame (PSR below
  ``hidden_psr``) is learnt too with ``learn_occluded``, as Staple learns every frame, when
  the colour response at its peak passes the same ``doubtful_colour`` check (MOSSE's PSR then
  says what the state is, not when to stop learning): a change of appearance (a face turning,
  a book rotating) drops the PSR below 7, and a model frozen there never took the target back
  (13 starts a sequence, tune 0.542 -> 0.556, check 0.510 -> 0.533); the colour check keeps a
  plain occluder out of the model (without it the generated `slab` fell from 0.72 to 0.67;
  benchmarks/RESULTS.md section 8, eighth round). LMCF's stricter test (Wang et al., CVPR
  2017, section 3.3: learn only when APCE and peak reach ``update_apce`` = 0.7 and
  ``update_peak`` = 0.45 of their means over the frames so far) froze the model through
  appearance changes here and lowered the mean AUC on both the tune and the check sequences:
  it is off by default (0), kept for the ablation. The learning rates (``rate``, and the
  colour's and the scale's) are per frame learnt, not per frame elapsed, as in Staple, DSST
  and MOSSE, whose models are running averages of the samples they learn from: a frame after
  a gap is one sample, and weighing it as the frames missed (``1 - (1 - rate)^k``) would let
  one look at the target (or at what hides it) replace that many frames of the model. LMCF's
  means (above) are over the frames given for the same reason: they describe the responses
  seen.

Pipeline contract of stage ``robust_failure``: reads ``ctx.measurement``, ``ctx.robust``,
``ctx.prediction``, ``ctx.state``, ``ctx.clock``; writes ``ctx.state``, ``ctx.box`` (with
``coast``, the prediction while hidden), ``ctx.measurement`` (None while hidden with ``coast``),
``ctx.search_growth``, ``ctx.robust`` (usual confidence, hidden frames, whether the next frame
searches the whole frame, whether this frame saw the target) and the ``psr`` column (its
confidence is the row's ``score``).
"""

from __future__ import annotations

from vtrack.frame import Frame
from vtrack.geometry import Box
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, TrackState, register
from vtrack.stages.robust_model import MAX_RINGS, RobustTarget


@register
class RobustFailure(Stage):
    """State from the correlation response (MOSSE's PSR); learning while tracking."""

    name = "robust_failure"
    summary = ("robust: occluded when the response's peak-to-sidelobe ratio is low (MOSSE), "
               "lost after a while; the model learns while the target is not lost and its "
               "colours agree")
    params = (
        Param("hidden_psr", float, 7.0, "occluded below this peak-to-sidelobe ratio (MOSSE: 7)",
              min=0.0, max=100.0),
        Param("hidden_peak", float, 0.45, "a sharp peak below this share of its mean so far is "
              "called occluded but still followed and learnt, and takes no hidden target back "
              "(LMCF beta_2: 0.45; 0: never)",
              min=0.0, max=10.0),
        Param("doubtful_colour", float, 0.0, "a doubtful frame is learnt only when the colour "
              "response at its peak is at least this share of its mean so far (LMCF beta_1: "
              "0.7; 0: always, as a tracking frame)", min=0.0, max=10.0),
        Param("retake_apce", float, 0.0, "a hidden target is taken back only on a response "
              "whose APCE is at least this share of its mean so far (LMCF beta_1: 0.7; 0: "
              "sharp and strong suffice)", min=0.0, max=10.0),
        Param("retake_colour", bool, False, "a hidden target is taken back only where the colour "
              "response at the peak passes doubtful_colour's check too (both learners agree)"),
        Param("lost_after", int, 30, "frames the target may stay hidden before it is lost "
              "(frames elapsed: frames missing from the input count, by their numbers or "
              "timestamps)", min=0, max=100000),
        Param("coast", bool, False, "while occluded, the box follows the motion model's "
              "prediction (false: it stays on the response's peak, unlearnt)"),
        Param("coast_unseen", bool, False, "on an occluded frame whose colour response at the "
              "peak fails doubtful_colour's check (neither learner sees the target), the box "
              "reported is the motion model's extrapolation from the last frame that saw it; "
              "the search stays at the peak"),
        Param("redetect", bool, True, "while lost, search regions around the last centre"),
        Param("redetect_on_colour", bool, False, "after a frame whose colour response at the "
              "peak fails doubtful_colour's check (or whose target that search found far "
              "away), also search where the merged response peaks over the whole frame "
              "(robust_model.filter_redetect's region), taken only with a peak at least the "
              "usual one"),
        Param("update", bool, True, "learn the models on confident tracking frames"),
        Param("learn_occluded", bool, False, "also learn an occluded (not lost) frame whose "
              "colour response at the peak passes doubtful_colour's check (Staple learns "
              "every frame; false: nothing is learnt below hidden_psr, MOSSE)"),
        Param("rate", float, 0.01, "correlation filter's learning rate (Staple: 0.01)",
              min=0.0, max=1.0),
        Param("update_apce", float, 0.0, "learn only at this share of the usual APCE or more "
              "(LMCF beta_1: 0.7; 0: on every tracking frame, as Staple)", min=0.0, max=10.0),
        Param("update_peak", float, 0.0, "... and this share of the usual peak (LMCF beta_2: "
              "0.45; 0: on every tracking frame)", min=0.0, max=10.0),
    )
    requires = frozenset({"measurement", "robust", "prediction", "state", "clock"})
    provides = frozenset({"state", "box", "measurement", "search_growth", "robust"})
    columns = ("psr",)

    hidden_psr: float
    hidden_peak: float
    doubtful_colour: float
    retake_apce: float
    retake_colour: bool
    lost_after: int
    coast: bool
    coast_unseen: bool
    redetect: bool
    redetect_on_colour: bool
    update: bool
    learn_occluded: bool
    rate: float
    update_apce: float
    update_peak: float

    def start(self, ctx: TrackContext) -> None:
        ctx.state = TrackState.TRACKING
        assert ctx.box is not None
        # a box with less than this share of its area inside the frame is leaving the view
        # (kept on the target: robust_motion reports no extrapolation past it either)
        assert ctx.robust is not None
        ctx.robust.least_inside = _leaving_share(ctx.box, ctx.frame)

    def step(self, ctx: TrackContext) -> None:
        target = ctx.robust
        assert target is not None
        try:
            self._judge(ctx, target)
        finally:  # the frame's last cut is done (its learning): its converted pixels go
            target.frame_done()

    def _judge(self, ctx: TrackContext, target: RobustTarget) -> None:
        """The frame's state from the response (the module docstring), and the models'
        learning."""
        ctx.extras["psr"] = target.psr
        # LMCF's means are of the frames before this one
        sharp = target.psr >= self.hidden_psr
        weak = target.peak < self.hidden_peak * target.usual_peak
        strong = self._strong(target)
        may_learn = self.update and strong  # the models may learn this frame
        was = ctx.state
        # the colour learner disagrees: the colour response at the peak is low for the target
        colour_disagrees = target.colour_peak < self.doubtful_colour * target.usual_colour
        retaken = target.hidden_frames == 0 or (
            not weak and target.apce >= self.retake_apce * target.usual_apce
            and not (self.retake_colour and colour_disagrees))
        _remember(target)
        # ... and a target just found far away may be as far again on the next frame
        found_far = target.chosen is not None and target.chosen.far
        target.search_wide = self.redetect_on_colour and (colour_disagrees or found_far)
        # a peak whose box lies mostly outside the frame is no sight of the target: it is
        # leaving the view (without this, weak peaks on the border it left by were followed
        # as doubtful frames, never lost, and strong ones on the replicated border past the
        # frame's edge were called tracking)
        off_frame = mostly_outside(ctx.measurement, ctx.frame, target.least_inside)
        target.unseen = False
        if (ctx.measurement is not None and sharp and retaken and not off_frame
                and (was == TrackState.TRACKING or strong)):
            target.hidden_frames, target.seen_at = 0, ctx.clock.frame
            ctx.search_growth = 1.0
            # a sharp but weak peak is doubtful: called occluded, yet followed and learnt as a
            # tracking frame (freezing the model there lost more targets than it kept: the
            # check sequences' mean AUC 0.606 -> 0.546), and no step towards lost
            ctx.state = TrackState.OCCLUDED if weak else TrackState.TRACKING
            if weak:
                _hold_size(target, ctx)
            elif target.least_inside < LEAVING:  # a target given entering the view: its
                # limit rises as it comes in
                target.least_inside = max(target.least_inside,
                                          _leaving_share(ctx.measurement, ctx.frame))
            if may_learn and not (weak and colour_disagrees):
                target.learn(ctx.frame, ctx.measurement, self.rate)
            return
        # time, not calls: frames missing from the input count as hidden too (whole frames
        # since the last sight: timestamps a fraction of a frame off do not add up); at least
        # one, since 0 means seen on the last frame (a frame stamped early rounds back to it)
        target.hidden_frames = max(ctx.clock.frame - target.seen_at, 1)
        _hold_size(target, ctx)
        if self.coast:
            ctx.measurement = None  # S0 sec. 3: coast on the prediction
            if ctx.prediction is not None:
                ctx.box = ctx.prediction
        gone = mostly_outside(ctx.box, ctx.frame, target.least_inside)
        lost = target.hidden_frames > self.lost_after or gone or was == TrackState.LOST
        ctx.state = TrackState.LOST if lost else TrackState.OCCLUDED
        target.unseen = self.coast_unseen and colour_disagrees and not lost
        if (may_learn and self.learn_occluded and not lost and ctx.measurement is not None
                and not colour_disagrees):
            target.learn(ctx.frame, ctx.measurement, self.rate)
        if lost and self.redetect:
            ctx.search_growth = min(ctx.search_growth + ctx.clock.whole_elapsed,
                                    MAX_RINGS + 1.0)

    def _strong(self, target: RobustTarget) -> bool:
        """LMCF's test: APCE and peak at their shares of the usual values (always true before
        anything was learnt after the first frame)."""
        if target.response_frames == 0:
            return True
        return (target.apce >= self.update_apce * target.usual_apce
                and target.peak >= self.update_peak * target.usual_peak)


def _hold_size(target: RobustTarget, ctx: TrackContext) -> None:
    """Keep the size of the frame before on a frame called occluded (hidden or doubtful): its
    scale samples show whatever hides the target (an occluder grew the box by half in a few
    frames). The measurement keeps its centre."""
    target.scale = target.previous_scale
    if ctx.measurement is not None:
        ctx.measurement = ctx.box = Box.from_center(ctx.measurement.cx, ctx.measurement.cy,
                                                    *target.size)


def _remember(target: RobustTarget) -> None:
    """LMCF's historical means of APCE and peak (and of the colour response at the peak):
    plain means over the frames so far (hidden ones too, so that a lasting change of appearance
    is taken in, slowly). The colour's mean also counts the first frame's response at the given
    box (``robust_search``), so its check holds from the first tracked frame on."""
    n = target.response_frames + 1
    target.usual_apce += (target.apce - target.usual_apce) / n
    target.usual_peak += (target.peak - target.usual_peak) / n
    target.response_frames = n
    target.colour_frames += 1
    target.usual_colour += (target.colour_peak - target.usual_colour) / target.colour_frames


#: A box with less than this share of its area inside the frame is leaving the view (a first
#: box partly outside lowers it to this share of its own inside share, until it comes in).
LEAVING = 0.5


def _leaving_share(box: Box, frame: Frame) -> float:
    """The inside share below which ``box``, seen now, would be leaving the view."""
    return LEAVING * min(_inside_share(box, frame), 1.0)


def mostly_outside(box: Box | None, frame: Frame, least: float) -> bool:
    """Whether less than ``least`` of ``box``'s area lies inside the frame (False without a
    box)."""
    return box is not None and _inside_share(box, frame) < least


def _inside_share(box: Box, frame: Frame) -> float:
    """The share of ``box``'s area that its pixels inside the frame cover (0 for none; whole
    pixels, so a sub-pixel box inside may give a little more than 1)."""
    window = box.window(frame.width, frame.height)
    if window is None or box.area <= 0:
        return 0.0
    return window.width * window.height / box.area
