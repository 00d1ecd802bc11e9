-- Why a registration is not in the graph, as a kind the core names (core/accept/rejection.h)
-- beside the words: refused by its own tests or the DR gate (rejection, reason), or accepted and
-- then left out by the back end (exclusion, exclusion_reason). And the pose each registration
-- started from (guess), so that a stored constraint is the whole of what the core produced.
ALTER TABLE constraints
  ADD COLUMN rejection        text NOT NULL DEFAULT 'none',
  ADD COLUMN exclusion        text NOT NULL DEFAULT 'none',
  ADD COLUMN exclusion_reason text NOT NULL DEFAULT '',
  ADD COLUMN guess            double precision[] NOT NULL DEFAULT '{1,0,0,0,0,0,0}' CHECK (cardinality(guess) = 7);

-- Rows stored before kinds: their reasons began with the words of their kind, numbers after.
UPDATE constraints SET
  rejection = CASE
    WHEN reason LIKE 'loop closure without features%' THEN 'loop closure without features'
    WHEN reason LIKE 'no overlapping points%' THEN 'no overlapping points'
    WHEN reason LIKE 'GICP did not converge%' THEN 'GICP did not converge'
    WHEN reason LIKE 'inlier ratio%' THEN 'inlier ratio'
    WHEN reason LIKE 'overlap MSE%' THEN 'overlap MSE'
    WHEN reason LIKE 'overlap points%' THEN 'overlap points'
    WHEN reason LIKE 'ambiguous (a second alignment%' THEN 'ambiguous: competing alignment'
    WHEN reason LIKE 'ambiguous%' THEN 'ambiguous: terrain not unique'
    WHEN reason LIKE 'translation from dead reckoning%' THEN 'translation from dead reckoning'
    ELSE 'implausible against dead reckoning'
  END
WHERE NOT accepted;

ALTER TABLE constraints ADD CONSTRAINT constraints_accepted_has_no_rejection CHECK (accepted = (rejection = 'none'));
