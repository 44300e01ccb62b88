;;;; Household demo runs for tools/cram-plans-run: one seeded run (spawn poses jittered in
;;;; their containers, the furniture varied), its end state checked object by object, and the
;;;; JSON record of a campaign run.

(in-package :cram-plans-demo)

(defparameter *household-spawn-jitter* 0.01d0
  "Metres by which a campaign run moves each spawn pose in its container (x and y, uniform).")

(defun jittered-spawning-poses (state)
  "DEMOS:*OBJECT-SPAWNING-POSES* with each position moved by up to *HOUSEHOLD-SPAWN-JITTER* in
x and y, drawn from STATE."
  (flet ((jitter () (- (random (* 2 *household-spawn-jitter*) state) *household-spawn-jitter*)))
    (loop for (type link ((x y z) q)) in demos:*object-spawning-poses*
          collect (list type link (list (list (+ x (jitter)) (+ y (jitter)) z) q)))))

(defun link-position (link)
  (cl-transforms:origin (btr:link-pose (btr:get-environment-object) link)))

(defparameter *household-end-places*
  '((:bowl :dishwasher) (:cup :dishwasher) (:spoon :dishwasher)
    (:breakfast-cereal "oven_area_area_right_drawer_board_3_link" 0.3d0)
    (:milk "sink_area_trash_drawer_main" 0.35d0))
  "(type link metres) or (type :dishwasher): where each object must end after cleaning, within
that distance of the link's origin, or in the dishwasher (DEMOS:IN-DISHWASHER-P).")

(defun household-end-state-problems (object-types)
  "What is wrong with the kitchen after a household demo of OBJECT-TYPES: objects away from
their place of *HOUSEHOLD-END-PLACES*, a container still open, an object still held. NIL when
all is well."
  (let ((problems '()))
    (dolist (type object-types)
      (let* ((o (btr:object btr:*current-bullet-world* (demos:demo-object-name type)))
             (place (assoc type *household-end-places*)))
        (cond ((null o) (push (format nil "~(~a~) is gone" type) problems))
              ((and place (eq (second place) :dishwasher))
               (unless (demos:in-dishwasher-p (cl-transforms:origin (btr:pose o)))
                 (push (format nil "~(~a~) is not in the dishwasher" type) problems)))
              (place
               (let ((d (cl-transforms:v-dist (cl-transforms:origin (btr:pose o))
                                              (link-position (second place)))))
                 (when (> d (third place))
                   (push (format nil "~(~a~) is ~,2f m from ~a" type d (second place)) problems)))))))
    (dolist (joint demos:*household-joints*)
      (let ((v (btr:joint-state (btr:get-environment-object) joint)))
        (when (> (abs v) 0.1d0)
          (push (format nil "~a is open (~,2f)" joint v) problems))))
    (let ((held (btr:attached-objects (btr:get-robot-object))))
      (when held (push (format nil "the robot still holds ~{~a~^, ~}" (mapcar #'first held)) problems)))
    (nreverse problems)))

(defun run-household (seed &key (object-types demos:*demo-object-types*) (varied t)
                             (log-stream (make-broadcast-stream)))
  "One household demo run drawn from SEED: spawn poses jittered, the kitchen varied (unless
VARIED is NIL). Returns a plist: :success, :failure (the condition's class or
\"end-state\"), :error (its text), :problems (of the end state), :sweeps (pairs of a moving
link or carried object and what its path hits), :seconds."
  (let* ((state (sb-ext:seed-random-state seed))
         (demos:*object-spawning-poses* (jittered-spawning-poses state))
         (demos::*varied-kitchen-random-state* (sb-ext:seed-random-state (+ seed 3)))
         (start (get-internal-real-time))
         (sweeps 0)
         (failure nil) (error nil))
    (seed-everything seed)
    (btw-tut:init-projection)
    (let ((cpl:*log-stream* log-stream)
          (urdf-proj:*sweep-hooks* (cons (lambda (sweep) (declare (ignore sweep)) (incf sweeps))
                                         urdf-proj:*sweep-hooks*)))
      (handler-case (demos:household-demo :object-list object-types :varied-kitchen varied
                                          :seed seed)
        (serious-condition (e)
          (setf failure (string-downcase (symbol-name (type-of e)))
                error (or (ignore-errors (princ-to-string e)) failure)))))
    (let ((problems (and (null failure) (household-end-state-problems object-types))))
      (list :success (and (null failure) (null problems))
            :failure (or failure (and problems "end-state"))
            :error (or error (and problems (format nil "~{~a~^; ~}" problems)))
            :problems problems
            :sweeps sweeps
            :seconds (float (/ (- (get-internal-real-time) start) internal-time-units-per-second)
                            1d0)))))

(defun household-run-record (campaign-seed index)
  "Run household demo number INDEX of the campaign CAMPAIGN-SEED; a hash table for one JSON
line (index, seed, success, failure type, error, seconds)."
  (let* ((seed (run-seed campaign-seed index))
         (result (run-household seed))
         (record (make-hash-table :test 'equal)))
    (setf (gethash "index" record) index
          (gethash "seed" record) seed
          (gethash "demo" record) "household"
          (gethash "success" record) (and (getf result :success) t)
          (gethash "failure" record) (getf result :failure)
          (gethash "seconds" record) (getf result :seconds)
          (gethash "sweeps" record) (getf result :sweeps 0)
          (gethash "error" record) (let ((e (getf result :error))) (and e (first-line e))))
    (dolist (key *recovery-keys*) (setf (gethash key record) 0))
    record))
