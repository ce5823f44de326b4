// Which joints and bones of a playback skeleton are drawn (no imports: tested with node).
//
// Some rigs (Bandai-Namco, many game rigs) put a placement joint at the root: zero offset, on the
// floor under the body, carrying the position channels, with the hips as its only child. It is no
// part of the body, and a bone from it to the hips would show a "third leg". A root with a single
// child is such a joint (a real pelvis root has at least the two thighs and the spine below it):
// neither it nor the bone from it is drawn.

// parents[j] is the parent of joint j (-1 for a root). Returns { bones, joints }: sets of the
// joint indices whose bone (to its parent) and whose sphere are hidden.
export function hiddenParts(parents) {
  const children = new Map();
  parents.forEach((p, j) => { if (p >= 0) children.set(p, [...(children.get(p) || []), j]); });
  const bones = new Set();
  const joints = new Set();
  parents.forEach((p, j) => {
    if (p >= 0) return;
    const below = children.get(j) || [];
    if (below.length === 1) { joints.add(j); bones.add(below[0]); }
  });
  return { bones, joints };
}
