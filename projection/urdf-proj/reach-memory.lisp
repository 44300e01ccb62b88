;;;; The reach memory: the robot states MOVE-TCP's search found for tool goals, offered first
;;;; when the same goals are asked for again from near the same base pose. A pre-check that
;;;; found how the hand reaches a grasp is then followed by a motion that reaches it the same
;;;; way, instead of searching again from another arm configuration (where the IK may settle on
;;;; a redundant solution that collides and miss the one the pre-check found).

(in-package :cram-urdf-projection)

(defparameter *reach-memory-size* 48
  "How many found reach states the reach memory of a projection run keeps (the newest).")

(defstruct (reach-memory (:constructor make-reach-memory ()))
  "The reach states found in one projection run, newest first (*REACH-MEMORY*)."
  (entries '() :type list)
  (lock (sb-thread:make-mutex :name "reach memory")))

(defvar *reach-memory* nil
  "NIL (no memory), or the REACH-MEMORY of the current projection run: every projection
environment starts with a fresh one, so that a run does not depend on the runs before it.")

(defstruct (reach-state (:constructor make-reach-state (robot goals base joints
                                                        &aux (hash (goals-hash goals)))))
  robot   ; the robot object
  goals   ; list of (arm . 7-vector of the tool frame's map pose)
  base    ; map pose of the base
  joints  ; ((joint value) ...): the torso and the arm joints
  (hash 0 :type fixnum)) ; GOALS-HASH of the goals

(deftype pose-7 () '(simple-array double-float (7)))

(defun pose-7 (pose)
  "POSE as a 7-vector of doubles: x y z, then the quaternion x y z w."
  (let ((o (cl-transforms:origin pose)) (q (cl-transforms:orientation pose))
        (v (make-array 7 :element-type 'double-float)))
    (setf (aref v 0) (cl-transforms:x o) (aref v 1) (cl-transforms:y o) (aref v 2) (cl-transforms:z o)
          (aref v 3) (cl-transforms:x q) (aref v 4) (cl-transforms:y q) (aref v 5) (cl-transforms:z q)
          (aref v 6) (cl-transforms:w q))
    v))

(defun same-pose-7-p (a b)
  "True when the 7-vectors A and B are the same pose (0.001 mm; a quaternion and its negation
are one rotation)."
  (declare (type pose-7 a b))
  (and (loop for i below 3 always (< (abs (- (aref a i) (aref b i))) 1d-6))
       (> (abs (loop with dot double-float = 0d0
                     for i from 3 below 7 do (incf dot (* (aref a i) (aref b i)))
                     finally (return dot)))
          (- 1d0 1d-12))))

(defun reach-goals-key (goals)
  "GOALS ((arm . tcp-map-pose) ...) as the reach memory compares them."
  (mapcar (lambda (g) (cons (car g) (pose-7 (cdr g)))) goals))

(defun goals-hash (goals)
  "A fixnum of GOALS (a REACH-GOALS-KEY) rounded to 0.1 mm and 1e-4 of the quaternion (sign
made positive): goals that are the same pose mostly have the same hash, so the memory compares
goals in full only when the hashes agree."
  (let ((h 17))
    (declare (type fixnum h))
    (dolist (g goals h)
      (let* ((v (cdr g)) (sign (if (minusp (aref v 6)) -1d0 1d0)))
        (declare (type pose-7 v) (type double-float sign))
        (setf h (logand most-positive-fixnum (+ (* h 31) (sxhash (car g)))))
        (dotimes (i 7)
          (let ((x (if (< i 3) (aref v i) (* sign (aref v i)))))
            (declare (type double-float x))
            (setf h (logand most-positive-fixnum
                            (+ (* h 31) (logand #xffffffff (round (/ x 1d-4))))))))))))

(defun same-goals-p (a b)
  "True when the REACH-GOALS-KEYs A and B name the same arms at the same poses."
  (loop for x = a then (cdr x) for y = b then (cdr y)
        while (and x y)
        always (and (eq (caar x) (caar y)) (same-pose-7-p (cdar x) (cdar y)))
        finally (return (and (null x) (null y)))))

(defun base-within-offsets-p (base base0 reach)
  "True when the map pose BASE is one MOVE-TCP may put the base at from BASE0: BASE0 shifted
\(same heading) by at most REACH (metres, 0: BASE0 itself) along each of its axes."
  (let* ((rel (cl-transforms:transform*
               (cl-transforms:transform-inv (cl-transforms:pose->transform base0))
               (cl-transforms:pose->transform base)))
         (d (cl-transforms:translation rel)))
    (and (< (abs (cl-transforms:z d)) 1d-6)
         (< (cl-transforms:angle-between-quaternions (cl-transforms:rotation rel)
                                                     (cl-transforms:make-identity-rotation))
            1d-6)
         (<= (abs (cl-transforms:x d)) (+ reach 1d-6))
         (<= (abs (cl-transforms:y d)) (+ reach 1d-6)))))

(defun recall-reach-state (robot goals base0 reach torso fixed-torso)
  "The newest remembered REACH-STATE of ROBOT for GOALS (a REACH-GOALS-KEY) that MOVE-TCP may
take from the base pose BASE0, its base moving by at most REACH (BASE-WITHIN-OFFSETS-P) and,
with FIXED-TORSO, without moving the joint TORSO; NIL when there is none."
  (let ((memory *reach-memory*))
    (when (and memory (reach-memory-entries memory))
      (let ((hash (goals-hash goals))
            (entries (sb-thread:with-mutex ((reach-memory-lock memory))
                       (reach-memory-entries memory))))
        (find-if (lambda (e)
                   (and (= (reach-state-hash e) hash)
                        (eq (reach-state-robot e) robot)
                        (same-goals-p (reach-state-goals e) goals)
                        (base-within-offsets-p (reach-state-base e) base0 reach)
                        (or (not fixed-torso) (null torso)
                            (let ((v (second (assoc torso (reach-state-joints e) :test #'equal))))
                              (or (null v) (< (abs (- v (btr:joint-state robot torso))) 1d-9))))))
                 entries)))))

(defun remember-reach-state (robot goals base joints)
  "Keep the state (base map pose BASE, JOINTS ((joint value) ...)) in which ROBOT reached
GOALS (a REACH-GOALS-KEY) in *REACH-MEMORY*, newest first, up to *REACH-MEMORY-SIZE*."
  (let ((memory *reach-memory*))
    (when memory
      (let* ((entry (make-reach-state robot goals base joints))
             (hash (reach-state-hash entry)))
        (sb-thread:with-mutex ((reach-memory-lock memory))
          ;; an older state for the same goals goes (the hashes compared first, as RECALL-REACH-STATE
          ;; compares them: an entry it cannot find again is left to age out)
          (let ((entries (cons entry (remove-if (lambda (e) (and (= (reach-state-hash e) hash)
                                                                  (eq (reach-state-robot e) robot)
                                                                  (same-goals-p (reach-state-goals e) goals)))
                                                (reach-memory-entries memory)))))
            (setf (reach-memory-entries memory)
                  (if (> (length entries) *reach-memory-size*)
                      (subseq entries 0 *reach-memory-size*)
                      entries))))))))

(defun forget-reach-states ()
  "Empty the reach memory of the current projection run (*REACH-MEMORY*)."
  (let ((memory *reach-memory*))
    (when memory
      (sb-thread:with-mutex ((reach-memory-lock memory))
        (setf (reach-memory-entries memory) '())))))
