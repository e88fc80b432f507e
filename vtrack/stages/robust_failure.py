"""The ``robust`` tracker's failure logic: tracking / occluded / lost, gated model update.

Third link of the ``robust`` chain (it runs before ``robust_motion``, which it tells whether to
update or coast, as S0's ``occlusion`` runs before ``kalman``). The signal is ``ctx.score``
(0..1, from ``robust_search``): each cue of the found box (template NCC, colour) relative to its
usual value, the running mean of that cue over confident frames, combined; so "0.5" means "half
as target-like as the target usually looks", whatever the target (Bolme et al., "Visual object
tracking using adaptive correlation filters", CVPR 2010, stop trusting MOSSE's peak the same
way, by its peak-to-sidelobe ratio).

- ``tracking`` while the score stays at or above ``occlude_below``; below it the measurement is
  withheld (the Kalman filter coasts, the box follows the prediction: S0 item 7) and the state
  is ``occluded``; after ``lost_after`` hidden frames it is ``lost``: no box is claimed (issue
  item 7), at once when the coasted box is mostly outside the frame (the target left the
  view), and with ``redetect`` the next frames search the whole frame at a coarse resolution
  (``robust_model.lost_pixels``) with a flat motion prior.
- A hidden target is taken back when the score of the best box reaches ``recover_at``
  (hysteresis against flicker).
- Model update (issue item 6, ``update``): on tracking frames whose score (``update_rule =
  score``) or both cues (``min``) reach ``update_above`` the colour histograms and the template
  are blended towards the box (:meth:`vtrack.stages.robust_model.RobustTarget.learn`, Staple's
  learning rates) and the usual cue values move ``rate_reference`` towards this frame's, never
  below ``reference_floor`` of the first frame's values; nothing is learnt while occluded or
  lost, so an occluder is not learnt as the target.
  ``trend_ratio`` (off by default) also stops learning while the score is below that share of
  its running mean (LMCF, Wang et al. CVPR 2017): it froze Car4's model through its lighting
  change (mean AUC 0.546 -> 0.48 on the real sequences), so it is only an option.
- Cue agreement (``agree_below``): a box is ``tracking`` only while BOTH cues, template and
  colour, reach that share of their usual values; a fair fused score carried by one cue alone
  (a box on an occluder with the target's grey texture, or on a same-coloured background) is
  not the target.
- Stale-template hold (``hold``): a TRACKING target whose template cue alone has fallen (the
  agreement test or the fused score fails) stays ``tracking`` while the colour cue still reaches
  ``hold_colour`` of its usual value AND the measurement lies inside the motion gate
  (Mahalanobis distance of the innovation in the predictor's uncertainty at most ``hold_gate``:
  Bar-Shalom, Li, Kirubarajan, "Estimation with Applications to Tracking and Navigation", 2001,
  sec. 5.4, validation gate; 3.03 is the 99% gate of a 2-D innovation). A template that went
  stale while the target turned is one cue disagreeing, not evidence that the target is gone;
  coasting there (and freezing the model) let the box drift off in a straight line and never
  recover. Held frames never take a hidden target back (that needs ``recover_at``).
- After a held frame the next one is localised on the colour map alone (``hold_search``): the
  stale template otherwise pulls the fused map's mode onto a placement half off the target
  whose background happens to match it (a re-check of the window by the cue that still sees
  the target, instead of the straight-line coast).
- Colour contrast (``ctx.robust.contrast``, from ``robust_search``): the found box's mean
  likelihood minus that of the ring around it, against its value on the first frame
  (``first_contrast``). Unlike the cues it is not relative to usual values that learning moves,
  so it cannot drift with them: a box that slid slowly off its target onto an occluder or bare
  background has lost it, whatever its score (the discriminability of a colour feature between
  the target and its surroundings, Collins, Liu, Leordeanu, "Online selection of
  discriminative tracking features", TPAMI 2005; the object-vs-surroundings ratio of DAT).
  Nothing is learnt below ``learn_contrast`` of it, and a box below ``unseen_contrast`` of it
  whose colour cue is also below its usual value does not show the target (occluded).
  Without these, a target covered slowly by a grey slab taught the model and the usual values
  the slab edge, and the box stayed on the slab with a score of 1, ``tracking``.
- A hidden target coming back into view is taken back on colour alone (``recover_colour``):
  colour cue and contrast near their usual and first values, inside the motion gate (anywhere
  while lost); the template, learnt on the whole target, matches a half-visible one badly.
- Held frames, and tracking frames below ``update_above`` that pass the same colour-and-motion
  test, blend the template only, at ``hold_rate`` (``hold_learn``; Staple and DSST learn every
  frame at a fixed rate, Bertinetto et al. 2016 eq. 5, Danelljan et al. BMVC 2014: the
  deadlock came from the hard ``update_above`` gate); the colour model and the usual cue values
  are not touched, so the hold cannot teach the colour cue what it then relies on.

Pipeline contract of stage ``robust_failure``: reads ``ctx.frame`` (its size), ``ctx.score``,
``ctx.measurement``, ``ctx.prediction``, ``ctx.robust`` (cues, usual values, contrast); writes
``ctx.state``, ``ctx.measurement`` / ``ctx.box`` (None / the prediction while hidden),
``ctx.robust`` (hidden count, usual cue values, whether the next frame searches the whole frame)
and the extra ``confidence``.
"""

from __future__ import annotations

from vtrack.geometry import Box
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, TrackState, register
from vtrack.stages.robust_model import RobustTarget


@register
class RobustFailure(Stage):
    """Occluded / lost from the relative score; confidence-gated model update."""

    name = "robust_failure"
    summary = ("robust: occluded below a relative confidence, lost after a while (no box, "
               "whole-frame re-detection), model update only on confident frames")
    params = (
        Param("occlude_below", float, 0.5,
              "tracking frames whose relative score falls below this are occluded",
              min=0.0, max=1.0),
        Param("recover_at", float, 0.65,
              "a hidden target is taken back at or above this relative score (>= "
              "occlude_below)", min=0.0, max=1.0),
        Param("lost_after", int, 90, "hidden frames after which the state is lost",
              min=1, max=100000),
        Param("redetect", bool, True,
              "while lost, search the whole frame (coarse) for the target"),
        Param("update", bool, True, "follow slow appearance change on confident frames"),
        Param("update_rule", str, "score",
              "what must reach update_above: score = this frame's score; min = each cue "
              "relative to its usual value", choices=("score", "min")),
        Param("update_above", float, 0.7, "relative score needed to update the model",
              min=0.0, max=1.0),
        Param("rate_hist", float, 0.04, "histogram learning rate (Staple: 0.04)",
              min=0.0, max=1.0),
        Param("rate_template", float, 0.01, "template learning rate (Staple: 0.01)",
              min=0.0, max=1.0),
        Param("rate_reference", float, 0.05,
              "learning rate of the reference confidence on confident frames",
              min=0.0, max=1.0),
        Param("reference_floor", float, 0.75,
              "the usual cue values never fall below this share of the first frame's",
              min=0.0, max=1.0),
        Param("trend_ratio", float, 0.0,
              "the model and the usual cue values learn only while the score is at least "
              "this share of its running mean over learning frames (LMCF's high-confidence "
              "update, Wang et al. CVPR 2017; 0: off)", min=0.0, max=1.0),
        Param("agree_below", float, 0.5,
              "occluded as soon as either cue (template, colour) falls below this share of "
              "its usual value: both cues must see the target (0: off)", min=0.0, max=1.0),
        Param("hold", bool, True,
              "keep a tracking target tracking while the colour cue is confident and the "
              "measurement is inside the motion gate, even when the template cue disagrees"),
        Param("hold_colour", float, 0.95,
              "share of its usual value the colour cue must reach for the hold",
              min=0.0, max=1.0),
        Param("hold_gate", float, 3.0,
              "largest Mahalanobis distance of the measured centre from the prediction "
              "(in the predictor's sigma per axis) for the hold", min=0.0, max=100.0),
        Param("hold_search", bool, True,
              "after a held frame, localise on the colour map alone (the stale template "
              "no longer pulls the box off the target)"),
        Param("hold_learn", bool, True,
              "on held frames, and on tracking frames below update_above that pass the hold "
              "test, blend the template (only) towards the box at hold_rate"),
        Param("hold_rate", float, 0.01,
              "template learning rate on held frames (Staple: 0.01)", min=0.0, max=1.0),
        Param("learn_contrast", float, 0.5,
              "the model and the usual cue values learn only while the box's colour contrast "
              "is at least this share of the first frame's (0: off)", min=0.0, max=1.0),
        Param("unseen_contrast", float, 0.25,
              "a box whose colour contrast is below this share of the first frame's, with "
              "its colour cue below its usual value, does not show the target (0: off)",
              min=0.0, max=1.0),
        Param("recover_colour", float, 0.8,
              "a hidden target is also taken back when its colour cue and colour contrast "
              "reach this share of their usual and first values, inside the motion gate "
              "(anywhere while lost; 0: off)", min=0.0, max=1.0),
    )
    requires = frozenset({"frame", "score", "measurement", "prediction", "robust"})
    provides = frozenset({"state", "measurement", "box"})
    columns = ("confidence",)

    # Set from the parameters by Stage.__init__.
    occlude_below: float
    recover_at: float
    lost_after: int
    redetect: bool
    update: bool
    update_rule: str
    update_above: float
    rate_hist: float
    rate_template: float
    rate_reference: float
    reference_floor: float
    trend_ratio: float
    agree_below: float
    hold: bool
    hold_colour: float
    hold_gate: float
    hold_search: bool
    hold_learn: bool
    hold_rate: float
    learn_contrast: float
    unseen_contrast: float
    recover_colour: float

    def start(self, ctx: TrackContext) -> None:
        """The first frame's box is the target: tracking."""
        ctx.state = TrackState.TRACKING
        assert ctx.robust is not None
        ctx.robust.hidden = 0
        ctx.robust.search_all = False
        ctx.robust.colour_only = False
        ctx.extras["confidence"] = 1.0
        self._usual = 1.0  # running mean of the score over learning frames (trend_ratio)

    def step(self, ctx: TrackContext) -> None:
        target = ctx.robust
        assert target is not None
        score = ctx.score
        ctx.extras["confidence"] = score
        level = self.occlude_below
        if ctx.state != TrackState.TRACKING:
            level = max(self.recover_at, self.occlude_below)  # hysteresis
        was_tracking = ctx.state == TrackState.TRACKING
        target.colour_only = False
        seen = self._seen(target)
        if ctx.measurement is not None and (
                (score >= level and self._agree(target) and seen)
                or (not was_tracking and self._emerging(ctx, target))):
            ctx.state = TrackState.TRACKING
            target.hidden = 0
            target.search_all = False
            if self.update and self._learnable(target, score):
                target.learn(ctx.measurement, self.rate_hist, self.rate_template)
                rate = self.rate_reference
                # the usual values follow slow change, down to reference_floor of what the
                # target scored at the start: a box scoring half of that is not "as usual",
                # however slowly it got there (a partly covered target, a drifting box)
                target.references = tuple(  # type: ignore[assignment]
                    max((1 - rate) * r + rate * v, self.reference_floor * first)
                    for r, v, first in zip(target.references, target.cues, target.first_cues,
                                           strict=True))
            elif self.update and self.hold_learn and self._held(ctx, target):
                # medium confidence, colour and motion agree: the template follows slowly
                target.learn_template(ctx.measurement, self.hold_rate)
            # the score's running mean over all tracking frames (LMCF's historical mean): a
            # lasting change of appearance lowers it and learning resumes
            self._usual = (1 - self.rate_reference) * self._usual + self.rate_reference * score
            return
        if was_tracking and seen and ctx.measurement is not None and self._held(ctx, target):
            # one stale cue is not evidence that the target is gone: follow the measurement
            # (the state stays tracking), localise the next frame on colour
            target.hidden = 0
            target.colour_only = self.hold_search
            if self.update and self.hold_learn:
                target.learn_template(ctx.measurement, self.hold_rate)
            return
        target.hidden += 1
        # S0 item 7: while hidden the measurement is not used and the box is the prediction
        ctx.measurement = None
        if ctx.prediction is not None:
            ctx.box = ctx.prediction
        gone = ctx.box is not None and _inside_share(ctx.box, ctx.frame.width,
                                                     ctx.frame.height) < 0.5
        # lost after lost_after hidden frames, or at once when the coasted box has left the
        # view (the target went out, or the prediction is wrong: no box to claim either way)
        lost = target.hidden > self.lost_after or gone
        ctx.state = TrackState.LOST if lost else TrackState.OCCLUDED
        target.search_all = lost and self.redetect

    def _learnable(self, target: RobustTarget, score: float) -> bool:
        """Whether this tracking frame may update the model: its score (``update_rule =
        score``) or BOTH cues relative to their usual values (``min``: a target being covered
        slowly keeps a fair fused score while one cue already sees the occluder) reach
        ``update_above``."""
        value = score if self.update_rule == "score" else target.confidence(target.cues, "min")
        # LMCF (Wang et al., "Large Margin Object Tracking with Circulant Feature Maps", CVPR
        # 2017, sec. 3.3): update only when the response is at least beta x its historical
        # mean, so a target being covered slowly (a falling score still above update_above)
        # does not teach the model and the usual values the occluder
        # and only while the box stands out from its surroundings in colour about as the
        # target did: the usual values follow the cues, so a box sliding slowly off its target
        # (each frame a little less target-like, each frame learnt) would otherwise drag them
        # down until bare background scored as usual; the contrast is measured against the
        # box's own ring with the current model and does not follow them down
        return (value >= self.update_above and score >= self.trend_ratio * self._usual
                and target.contrast >= self.learn_contrast * target.first_contrast)

    def _held(self, ctx: TrackContext, target: RobustTarget) -> bool:
        """Whether a tracking target whose template cue disagrees is still plainly there: the
        colour cue at ``hold_colour`` of its usual value and the measured centre inside the
        ``hold_gate`` validation gate around the prediction (Bar-Shalom et al. 2001, sec.
        5.4; the predictor's sigma per axis, ``ctx.robust.sigma``)."""
        colour, usual = target.cues[1], target.references[1]
        return (self.hold and colour >= self.hold_colour * max(usual, 1e-6)
                and self._gated(ctx, target))

    def _seen(self, target: RobustTarget) -> bool:
        """Whether the found box shows the target's colours against its surroundings: its
        colour contrast at least ``unseen_contrast`` of the first frame's, or its colour cue at
        its usual value (a grey target on a background of its own grey keeps its usual colour
        score but little contrast; that is not evidence that it is gone)."""
        return (target.contrast >= self.unseen_contrast * target.first_contrast
                or target.cues[1] >= target.references[1])

    def _emerging(self, ctx: TrackContext, target: RobustTarget) -> bool:
        """Whether a hidden target is coming back into view: the colour cue and the colour
        contrast of the found box at ``recover_colour`` of their usual and first values, inside
        the motion gate (anywhere while lost). A target coming out from behind an occluder
        shows its colours well before the template, learnt on the whole target, matches it
        again."""
        return (self.recover_colour > 0
                and target.cues[1] >= self.recover_colour * target.references[1]
                and target.contrast >= self.recover_colour * target.first_contrast
                and (ctx.state == TrackState.LOST or self._gated(ctx, target)))

    def _gated(self, ctx: TrackContext, target: RobustTarget) -> bool:
        """Whether the measured centre lies inside the ``hold_gate`` validation gate around
        the prediction (Bar-Shalom et al. 2001, sec. 5.4; the predictor's sigma per axis)."""
        if ctx.measurement is None or ctx.prediction is None:
            return False
        sx, sy = (max(s, 1e-6) for s in target.sigma)
        dx = (ctx.measurement.cx - ctx.prediction.cx) / sx
        dy = (ctx.measurement.cy - ctx.prediction.cy) / sy
        return dx * dx + dy * dy <= self.hold_gate ** 2

    def _agree(self, target: RobustTarget) -> bool:
        """Whether both cues see the target: each at least ``agree_below`` of its usual value.
        The template and colour cues fail in different ways (Bertinetto et al., Staple, CVPR
        2016, sec. 1): a box on an occluder that shares the target's texture or grey level
        keeps a fair fused score while one cue has collapsed; that is not the target."""
        if self.agree_below <= 0:
            return True
        return all(v >= self.agree_below * max(r, 1e-6)
                   for v, r in zip(target.cues, target.references, strict=True))


def _inside_share(box: Box, width: int, height: int) -> float:
    """Share of ``box``'s area inside a ``width`` x ``height`` frame."""
    w = min(box.x + box.w, width) - max(box.x, 0.0)
    h = min(box.y + box.h, height) - max(box.y, 0.0)
    return max(w, 0.0) * max(h, 0.0) / box.area if box.area > 0 else 0.0
