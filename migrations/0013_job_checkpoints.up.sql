-- Jobs that resume (issue 35): the register stage's batches as a running job registers them, so
-- that the job's next attempt after a crash or a lost lease takes them up instead of registering
-- them again. Written under the job's lease; removed when the job ends (succeeded, failed by its
-- worker, cancelled). The bytes carry a layout version (core/pipeline/registration_checkpoint.h):
-- an attempt that cannot read them registers the batch again.
CREATE TABLE job_checkpoints (
  job_id      bigint NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  batch_begin integer NOT NULL CHECK (batch_begin >= 0),
  batch_end   integer NOT NULL CHECK (batch_end > batch_begin),
  data        bytea NOT NULL,
  PRIMARY KEY (job_id, batch_begin)
);
