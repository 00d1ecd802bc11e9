-- Watchers of a job (WatchJob) are woken when something happens to it instead of polling:
-- every new job event and every change of a job's state notifies 'bathyslam_job_events' with
-- the job's id. NOTIFY is delivered at commit, so a woken watcher finds the rows.
CREATE FUNCTION notify_job_event() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
  PERFORM pg_notify('bathyslam_job_events', NEW.job_id::text);
  RETURN NULL;
END $$;

CREATE FUNCTION notify_job_state() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
  PERFORM pg_notify('bathyslam_job_events', NEW.id::text);
  RETURN NULL;
END $$;

CREATE TRIGGER job_events_notify AFTER INSERT ON job_events
  FOR EACH ROW EXECUTE FUNCTION notify_job_event();

CREATE TRIGGER jobs_state_notify AFTER UPDATE OF state ON jobs
  FOR EACH ROW WHEN (OLD.state IS DISTINCT FROM NEW.state) EXECUTE FUNCTION notify_job_state();
