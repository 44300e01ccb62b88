;;;; Timelines (CRAM's temporal reasoning): a time-ordered list of events, each with the world
;;;; state after it, and Prolog predicates that ask what held at a time.

(in-package :cram-bullet-reasoning)

(defclass event ()
  ((event :initarg :event :reader event
          :documentation "The pattern describing the event, e.g. (object-placed mug-1).")
   (world-state :initarg :world-state :reader event-world-state
                :documentation "The WORLD-STATE of the world after the event.")
   (timestamp :initarg :timestamp :reader timestamp
              :documentation "When the event happened (a real, seconds)."))
  (:documentation "An event of a TIMELINE and the world state it left."))

(defmethod print-object ((e event) stream)
  (print-unreadable-object (e stream :type t)
    (format stream "~s at ~a" (event e) (timestamp e))))

(defun make-event (world event-pattern &optional (timestamp (timeline-clock)))
  "An EVENT described by EVENT-PATTERN whose world state is WORLD's state now (WORLD is not
changed). TIMESTAMP defaults to the current Unix time."
  (unless (typep world 'bt-reasoning-world)
    (btr-fail "MAKE-EVENT: ~s is not a Bullet world" world))
  (unless (realp timestamp)
    (btr-fail "MAKE-EVENT: the timestamp ~s is not a real number (seconds)" timestamp))
  (make-instance 'event :event event-pattern :world-state (world-state world)
                        :timestamp timestamp))

(defun timeline-clock ()
  "The current Unix time in seconds, as a double float."
  (multiple-value-bind (seconds microseconds) (sb-ext:get-time-of-day)
    (+ seconds (/ microseconds 1d6))))

(defclass timeline ()
  ((events :initform '() :accessor %timeline-events
           :documentation "The events, oldest first.")
   (lock :initform (bt:make-lock "timeline") :reader timeline-lock))
  (:documentation "A time-ordered sequence of EVENTs; the last one holds the current state."))

(defun timeline-events (timeline)
  "The events of TIMELINE, oldest first."
  (bt:with-lock-held ((timeline-lock timeline))
    (copy-list (%timeline-events timeline))))

(defmethod print-object ((tl timeline) stream)
  (print-unreadable-object (tl stream :type t :identity t)
    (format stream "~d events" (length (%timeline-events tl)))))

(defun check-timeline (timeline function)
  (unless (typep timeline 'timeline)
    (btr-fail "~s: ~s is not a timeline (see TIMELINE-INIT)" function timeline)))

(defun timeline-advance (timeline event)
  "Add EVENT to TIMELINE at the place its timestamp gives (after the events of the same time);
return TIMELINE."
  (check-timeline timeline 'timeline-advance)
  (unless (typep event 'event)
    (btr-fail "TIMELINE-ADVANCE: ~s is not an event (see MAKE-EVENT)" event))
  (bt:with-lock-held ((timeline-lock timeline))
    (let ((events (%timeline-events timeline)))
      (setf (%timeline-events timeline)
            (let ((position (position-if (lambda (e) (> (timestamp e) (timestamp event))) events)))
              (if position
                  (append (subseq events 0 position) (list event) (nthcdr position events))
                  (append events (list event)))))))
  timeline)

(defun timeline-init (world &optional (time 0d0))
  "A new TIMELINE whose first event, START at TIME, holds WORLD's state now."
  (timeline-advance (make-instance 'timeline) (make-event world 'start time)))

(defun timeline-current-world-state (timeline)
  "The world state of the last event of TIMELINE."
  (check-timeline timeline 'timeline-current-world-state)
  (let ((last (car (last (timeline-events timeline)))))
    (and last (event-world-state last))))

(defun timeline-lookup (timeline stamp)
  "The world state at time STAMP: that of the last event of TIMELINE not later than STAMP (the
first event's state for an earlier STAMP)."
  (check-timeline timeline 'timeline-lookup)
  (unless (realp stamp)
    (btr-fail "TIMELINE-LOOKUP: the time ~s is not a real number" stamp))
  (let ((events (timeline-events timeline)))
    (event-world-state
     (or (find-if (lambda (e) (<= (timestamp e) stamp)) events :from-end t)
         (first events)))))

(defvar *current-timeline* nil
  "The timeline the Prolog predicates TIMELINE, OCCURS-IN and HOLDS-AT use; made from the
current world by the first query that needs it.")

(defmacro with-timeline (timeline &body body)
  "Evaluate BODY with *CURRENT-TIMELINE* bound to TIMELINE."
  `(let ((*current-timeline* ,timeline))
     ,@body))

(defun current-timeline ()
  "*CURRENT-TIMELINE*, made from *CURRENT-BULLET-WORLD* when there is none yet."
  (or *current-timeline*
      (setf *current-timeline* (timeline-init *current-bullet-world*))))

(defun solutions-in-state (state goal bindings)
  "The solutions (forced) of GOAL under BINDINGS in a copy of the current world put into STATE;
when GOAL's first argument is a variable (?w), it is that world."
  (let ((copy (copy-world *current-bullet-world*)))
    (unwind-protect
         (let ((*current-bullet-world* copy))
           (restore-world-state state copy)
           (cut:force-ll (prolog (if (and (consp goal) (consp (cdr goal)) (cut:is-var (second goal)))
                                     `(and (bullet-world ,(second goal)) ,goal)
                                     goal)
                                 bindings)))
      (destroy-world copy))))

(def-prolog-handler holds-in-world-state (bindings ?state ?goal)
  (let ((state (cut:var-value ?state bindings))
        (goal (cut:var-value ?goal bindings)))
    (when (or (cut:is-var state) (cut:is-var goal))
      (btr-fail "HOLDS-IN-WORLD-STATE needs a bound world state and goal, got ~s and ~s"
                state goal))
    (solutions-in-state state goal bindings)))

(def-fact-group timeline-facts ()
  (<- (timeline ?timeline)
    (not (bound ?timeline))
    (lisp-fun current-timeline ?timeline))
  (<- (timeline ?timeline)
    (bound ?timeline)
    (lisp-type ?timeline timeline))

  ;; (occurs-in ?timeline ?event ?time): ?event happened at ?time
  (<- (occurs-in ?timeline ?event ?time)
    (timeline ?timeline)
    (lisp-fun timeline-events ?timeline ?events)
    (member ?instance ?events)
    (lisp-fun timestamp ?instance ?time)
    (lisp-fun event ?instance ?event))

  ;; (holds-at ?timeline ?goal ?time): ?goal held in the world at ?time (every event time when
  ;; ?time is unbound)
  (<- (holds-at ?timeline ?goal ?time)
    (bound ?time)
    (timeline ?timeline)
    (lisp-fun timeline-lookup ?timeline ?time ?state)
    (holds-in-world-state ?state ?goal))
  (<- (holds-at ?timeline ?goal ?time)
    (not (bound ?time))
    (occurs-in ?timeline ?_ ?time)
    (holds-at ?timeline ?goal ?time)))

(setf (documentation 'event 'function) "The pattern describing an EVENT."
      (documentation 'event-world-state 'function) "The world state an EVENT left."
      (documentation 'timestamp 'function) "When an EVENT happened (seconds)."
      (documentation 'occurs-in 'function)
      "Prolog predicate (occurs-in ?timeline ?event ?time): ?event happened at ?time."
      (documentation 'holds-at 'function)
      "Prolog predicate (holds-at ?timeline ?goal ?time): ?goal held in the world at ?time.")
