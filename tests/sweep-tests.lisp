;;;; Tests of the sweep checks: what the simulated robot passes through between key poses
;;;; (cram-native:robot-sweep-check and urdf-proj:*sweep-check*).

(defpackage :cram-plans-tests.sweep
  (:use :cl :fiveam))

(in-package :cram-plans-tests.sweep)

(def-suite sweep :in cram-plans-tests:all
  :description "Sweep checks between key poses: native sweeps, motions under :warn and :fail.")

(in-suite sweep)

(defvar *resources* (asdf:system-relative-pathname "cram-plans/cram-urdf-projection" "resources/"))
(defvar *robots* (asdf:system-relative-pathname "cram-plans/cram-urdf-projection" "robots/"))

(defparameter *right-park* '(-1.712587449591307d0 -0.2567290370386635d0 -1.4633501125737374d0
                             -2.1221670650093913d0 1.7663253481913623d0 -0.07942669250968948d0
                             0.05106258161229582d0))
(defparameter *right-out* '(-0.4d0 0d0 0d0 -0.15d0 0d0 -0.1d0 0d0)
  "The right arm stretched out forwards.")

(defun make-open-world (&key kitchen)
  "A fresh world: the floor and the PR2 at the origin (and the kitchen with KITCHEN)."
  (rob-int:set-robot-name :pr2)
  (setf btr:*current-bullet-world* (make-instance 'btr:bt-reasoning-world))
  (let ((w btr:*current-bullet-world*))
    (btr:add-object w :static-plane :floor '((0 0 0) (0 0 0 1)) :normal '(0 0 1) :constant 0)
    (when kitchen
      (btr:add-object w :urdf :iai-kitchen '((0 0 0) (0 0 0 1))
                      :urdf (uiop:read-file-string (merge-pathnames "iai_kitchen.urdf" *resources*))
                      :collision-group :static-filter
                      :collision-mask '(:default-filter :character-filter)))
    (btr:add-object w :urdf :pr2 '((0 0 0) (0 0 0 1))
                    :urdf (uiop:read-file-string (merge-pathnames "pr2/pr2.urdf" *robots*)))
    w))

(defmacro with-open-world ((&key kitchen) &body body)
  `(let ((btr:*current-bullet-world* btr:*current-bullet-world*)
         (rob-int:*robot-name* rob-int:*robot-name*)
         (urdf-proj:*sweep-check* urdf-proj:*sweep-check*))
     (make-open-world :kitchen ,kitchen)
     ,@body))

(defun robot () (btr:get-robot-object))

(defun set-right-arm (values)
  (btr:set-robot-state-from-joints (mapcar #'list (urdf-proj:arm-joint-names :right) values) (robot)))

(defun right-arm () (mapcar (lambda (j) (btr:joint-state (robot) j)) (urdf-proj:arm-joint-names :right)))

(defun mix (a b f) (mapcar (lambda (x y) (+ x (* f (- y x)))) a b))

(defun point-on-link (link x)
  "The map point X metres along LINK's x axis."
  (cl-transforms:transform-point (cl-transforms:pose->transform (btr:link-pose (robot) link))
                                 (cl-transforms:make-3d-vector x 0 0)))

(defun add-box (name point size)
  (let ((p point))
    (btr:add-object btr:*current-bullet-world* :box name
                    `((,(cl-transforms:x p) ,(cl-transforms:y p) ,(cl-transforms:z p)) (0 0 0 1))
                    :size size :mass 0)))

(defun robot-touches (name)
  (member name (urdf-proj:robot-collisions)))

(defun add-board ()
  "A board where the right forearm passes half way from park to stretched out, touching the
arm at neither end."
  (set-right-arm (mix *right-park* *right-out* 0.5))
  (add-box 'board (point-on-link "r_forearm_link" 0.2) '(0.3 0.3 0.02))
  (set-right-arm *right-park*)
  'board)

(defun recorded-sweeps (thunk)
  "Call THUNK; return the sweeps reported meanwhile (oldest first) and THUNK's outcome, a
condition or :OK."
  (let* ((seen '())
         (urdf-proj:*sweep-hooks* (cons (lambda (s) (push s seen)) urdf-proj:*sweep-hooks*))
         (outcome (handler-case (progn (funcall thunk) :ok)
                    (cpl:plan-failure (f) f))))
    (values (reverse seen) outcome)))

;;; ---- the native call ---------------------------------------------------------------------------

(test native-robot-sweep-check-finds-the-board
  (with-open-world ()
    (add-board)
    (let* ((w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot)))
           (base (cram-native:object-pose w r))
           (q0 (cram-native:robot-joints w r)))
      (is (null (robot-touches 'board)))
      (set-right-arm *right-out*)
      (is (null (robot-touches 'board)))
      (let* ((q1 (cram-native:robot-joints w r))
             (hits (cram-native:robot-sweep-check w r base q0 base q1))
             (board (btr:object-handle (btr:object btr:*current-bullet-world* 'board))))
        (is (plusp (length hits)))
        (is (every (lambda (h) (= (third h) board)) hits))
        (is (member "r_forearm_link" hits :test #'string=
                                          :key (lambda (h) (btr::link-name-of (robot) (second h)))))
        (is (every (lambda (h) (< 0 (fifth h) 1)) hits))
        ;; the robot in the world stays where it was
        (is (every #'= q1 (cram-native:robot-joints w r)))
        ;; the other way back finds it as well, and ignoring the board hides it
        (is (plusp (length (cram-native:robot-sweep-check w r base q1 base q0))))
        (is (null (cram-native:robot-sweep-check w r base q0 base q1 :ignore (list (list -1 -1 board -1)))))))))

(test native-sweep-check-bad-input
  (with-open-world ()
    (let* ((w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot)))
           (base (cram-native:object-pose w r)) (q (cram-native:robot-joints w r)))
      (flet ((message (thunk)
               (handler-case (progn (funcall thunk) nil)
                 (cram-native:native-error (e) (princ-to-string e)))))
        (is (search "expected" (message (lambda () (cram-native:robot-sweep-check w r base '(1 2) base '(1 2))))))
        (is (search "maximum step is 0" (message (lambda () (cram-native:robot-sweep-check w r base q base q :max-step 0)))))
        (is (search ":BOGUS" (message (lambda () (cram-native:robot-sweep-check w r base q base q :ignore '(:bogus))))))
        (is (search "foo" (message (lambda () (cram-native:robot-sweep-check w r base q base q :tolerance "foo")))))
        (is (search "12345" (message (lambda () (cram-native:robot-sweep-check w 12345 base q base q)))))
        (is (search "(1 2 3)" (message (lambda () (cram-native:body-sweep-check w r '(1 2 3) base)))))))))

;;; ---- motions under *sweep-check* -----------------------------------------------------------

(test board-swept-by-the-forearm-warns
  (with-open-world ()
    (add-board)
    (setf urdf-proj:*sweep-check* :warn)
    (let ((log (make-string-output-stream)))
      (multiple-value-bind (sweeps outcome)
          (let ((cpl:*log-stream* log))
            (recorded-sweeps (lambda () (urdf-proj:move-joints nil *right-out*))))
        (is (eq :ok outcome))
        (is (every (lambda (a b) (< (abs (- a b)) 1d-6)) *right-out* (right-arm)))
        (is (plusp (length sweeps)))
        (is (every (lambda (s) (eq 'board (urdf-proj:sweep-hit s))) sweeps))
        (is (find "r_forearm_link" sweeps :key #'urdf-proj:sweep-moving-link :test #'equal))
        (let ((lines (remove-if-not (lambda (l) (search "SWEEP" l))
                                    (uiop:split-string (get-output-stream-string log) :separator '(#\Newline)))))
          (is (= 1 (length lines)))
          (is (search "board" (first lines)))
          (is (search "of the way" (first lines))))))))

(test board-swept-by-the-forearm-fails-and-stays
  (with-open-world ()
    (add-board)
    (setf urdf-proj:*sweep-check* :fail)
    (multiple-value-bind (sweeps outcome) (recorded-sweeps (lambda () (urdf-proj:move-joints nil *right-out*)))
      (is (typep outcome 'common-fail:manipulation-pose-unreachable))
      (let ((text (princ-to-string outcome)))
        (is (search "board" text))
        (is (search "_link" text))
        (is (search "of the way" text)))
      (is (plusp (length sweeps)))
      (is (every (lambda (a b) (< (abs (- a b)) 1d-9)) *right-park* (right-arm))))
    ;; nothing is checked with NIL
    (setf urdf-proj:*sweep-check* nil)
    (multiple-value-bind (sweeps outcome) (recorded-sweeps (lambda () (urdf-proj:move-joints nil *right-out*)))
      (is (eq :ok outcome))
      (is (null sweeps)))))

(test tool-frame-motion-through-the-board-fails-and-stays
  (with-open-world ()
    (set-right-arm *right-out*)
    (let ((goal (btr:link-pose (robot) (urdf-proj:tool-frame :right)))
          (solution nil))
      ;; the arm configuration the tool-frame motion reaches from park; the board goes where
      ;; the forearm passes half way there
      (set-right-arm *right-park*)
      (let ((urdf-proj:*sweep-check* nil))
        (urdf-proj:move-tcp nil goal :move-base nil :fixed-torso t))
      (setf solution (right-arm))
      ;; the first placement along the way that touches the arm at neither end
      (is (loop for (f x) in (loop for f in '(0.5 0.4 0.6 0.3 0.7) append (loop for x in '(0.2 0.1 0.3) collect (list f x)))
                thereis (progn
                          (set-right-arm (mix *right-park* solution f))
                          (add-box 'board (point-on-link "r_forearm_link" x) '(0.1 0.1 0.02))
                          (set-right-arm solution)
                          (let ((clear-at-end (null (robot-touches 'board))))
                            (set-right-arm *right-park*)
                            (or (and clear-at-end (null (robot-touches 'board)))
                                (progn (btr:remove-object btr:*current-bullet-world* 'board) nil))))))
      (setf urdf-proj:*sweep-check* :fail)
      ;; one candidate only (no base offsets, no torso change): its path crosses the board
      (multiple-value-bind (sweeps outcome)
          (recorded-sweeps (lambda () (urdf-proj:move-tcp nil goal :move-base nil :fixed-torso t)))
        (is (typep outcome 'common-fail:manipulation-pose-unreachable))
        (is (search "board" (princ-to-string outcome)))
        (is (plusp (length sweeps)))
        (is (every (lambda (s) (eq :tcp (urdf-proj:sweep-kind s))) sweeps))
        (is (every (lambda (a b) (< (abs (- a b)) 1d-9)) *right-park* (right-arm))))
      ;; under :warn the same motion moves and reports
      (setf urdf-proj:*sweep-check* :warn)
      (let ((cpl:*log-stream* (make-broadcast-stream)))
        (multiple-value-bind (sweeps outcome)
            (recorded-sweeps (lambda () (urdf-proj:move-tcp nil goal :move-base nil :fixed-torso t)))
          (is (eq :ok outcome))
          (is (plusp (length sweeps))))))))

(test allowed-contacts-are-not-reported
  (with-open-world ()
    (add-board)
    (setf urdf-proj:*sweep-check* :fail)
    (multiple-value-bind (sweeps outcome)
        (recorded-sweeps (lambda ()
                           (urdf-proj:with-allowed-sweep-contacts ((list t 'board))
                             (urdf-proj:move-joints nil *right-out*))))
      (is (eq :ok outcome))
      (is (null sweeps)))
    ;; allowing one link only leaves the others' sweeps
    (set-right-arm *right-park*)
    (multiple-value-bind (sweeps outcome)
        (recorded-sweeps (lambda ()
                           (urdf-proj:with-allowed-sweep-contacts ('("r_forearm_link" board))
                             (urdf-proj:move-joints nil *right-out*))))
      (declare (ignore outcome))
      (is (not (find "r_forearm_link" sweeps :key #'urdf-proj:sweep-moving-link :test #'equal))))
    (set-right-arm *right-park*)
    (let ((urdf-proj:*sweep-allowed-contacts* '(("no_such_link" board))))
      (signals error (urdf-proj:move-joints nil *right-out*)))
    (set-right-arm *right-park*)
    (let ((urdf-proj:*sweep-check* :loud))
      (handler-case (progn (urdf-proj:move-joints nil *right-out*) (fail "no error"))
        (error (e) (is (search ":LOUD" (princ-to-string e))))))
    (set-right-arm *right-park*)
    (let ((urdf-proj:*sweep-allowed-contacts* '((t no-such-object))))
      (handler-case (progn (urdf-proj:move-joints nil *right-out*) (fail "no error"))
        (error (e) (is (search "NO-SUCH-OBJECT" (princ-to-string e))))))))

(test one-notion-of-intended-contacts-for-both-checks
  "The contacts a plan declares are left out of the collision check at a key pose and of the
sweep check on the way, whichever way they are declared: *SWEEP-ALLOWED-CONTACTS* or the
pick-and-place plans' *GRASPED-OBJECTS* / *PLACED-OBJECTS*."
  (with-open-world ()
    ;; a box the stretched-out right forearm rests in
    (set-right-arm *right-out*)
    (add-box 'crate (point-on-link "r_forearm_link" 0.2) '(0.1 0.1 0.1))
    (is (robot-touches 'crate) "the forearm in the crate is a collision")
    (urdf-proj:with-allowed-sweep-contacts ('("r_forearm_link" crate))
      (is (not (robot-touches 'crate)) "an allowed (link object) pair is no collision either"))
    (urdf-proj:with-allowed-sweep-contacts ('("l_forearm_link" crate))
      (is (robot-touches 'crate) "allowing another link leaves the collision"))
    (let ((urdf-proj:*grasped-objects* '(crate)))
      (is (robot-touches 'crate) "the forearm is no hand: grasping the crate does not excuse it")
      (is (find '("r_gripper_palm_link" crate)
                (urdf-proj::intended-contacts (robot)) :test #'equal)
          "a grasped object is an intended contact of each hand link")))
  (with-open-world ()
    ;; the board the forearm sweeps through, declared as the object the hands close in on:
    ;; the forearm's sweep is still reported, the hand links' are not
    (add-board)
    (setf urdf-proj:*sweep-check* :warn)
    (let ((plain (recorded-sweeps (lambda () (urdf-proj:move-joints nil *right-out*)))))
      (set-right-arm *right-park*)
      (let ((grasping (let ((urdf-proj:*grasped-objects* '(board)))
                        (recorded-sweeps (lambda () (urdf-proj:move-joints nil *right-out*)))))
            (hands (urdf-proj::all-hand-links (robot))))
        (is (find "r_forearm_link" grasping :key #'urdf-proj:sweep-moving-link :test #'equal))
        (is (some (lambda (sw) (member (urdf-proj:sweep-moving-link sw) hands :test #'equal)) plain)
            "without the grasp, hand links sweep the board: ~s"
            (mapcar #'urdf-proj:sweep-moving-link plain))
        (is (notany (lambda (sw) (member (urdf-proj:sweep-moving-link sw) hands :test #'equal))
                    grasping)
            "hand links sweeping the grasped object are reported")
        (is (<= (length grasping) (length plain)))))))

;; a stick held in the right hand (parked), reaching 0.3 m down from the tool frame
(defun hold-stick ()
  (let ((tool (cl-transforms:origin (btr:link-pose (robot) "r_gripper_tool_frame"))))
    (btr:add-object btr:*current-bullet-world* :box 'stick
                    `((,(cl-transforms:x tool) ,(cl-transforms:y tool) ,(- (cl-transforms:z tool) 0.16)) (0 0 0 1))
                    :size '(0.02 0.02 0.3) :mass 0.1)
    (btr:attach-object (robot) 'stick :link "r_gripper_tool_frame")))

;; where SWEEP's moving link or carried object is now, as (x y z)
(defun moving-frame-xyz (robot sweep)
  (let ((p (cl-transforms:origin
            (if (urdf-proj:sweep-moving-link sweep)
                (btr:link-pose robot (urdf-proj:sweep-moving-link sweep))
                (btr:pose (btr:object (btr:world robot) (urdf-proj:sweep-moving sweep)))))))
    (list (cl-transforms:x p) (cl-transforms:y p) (cl-transforms:z p))))

;; a board 0.2 m below the tool frame of the right arm half stretched out, the arm parked
;; again and holding a stick (HOLD-STICK): stretching the arm out sweeps the stick through it
(defun board-below-the-reach-and-stick ()
  (set-right-arm (mix *right-park* *right-out* 0.5))
  (let ((palm (btr:link-pose (robot) "r_gripper_tool_frame")))
    (add-box 'board (cl-transforms:v+ (cl-transforms:origin palm) (cl-transforms:make-3d-vector 0 0 -0.2))
             '(0.3 0.3 0.02)))
  (set-right-arm *right-park*)
  (hold-stick))

(test carried-object-through-the-board
  (with-open-world ()
    (board-below-the-reach-and-stick)
    (setf urdf-proj:*sweep-check* :warn)
    (is (null (urdf-proj:robot-collisions)))
    (let ((sweeps (recorded-sweeps (lambda () (urdf-proj:move-joints nil *right-out*)))))
      (is (find 'stick sweeps :key #'urdf-proj:sweep-moving))
      (is (every (lambda (s) (or (urdf-proj:sweep-moving-link s) (eq 'stick (urdf-proj:sweep-moving s)))) sweeps)))))

(defun moved-frame-path (sweep before after)
  "SWEEP's path as the robot itself gives it: set to the 17 states of the motion from BEFORE to
AFTER one after the other (the base on a straight line, turned by slerp, the joints linearly),
the moving link's or carried object's position read at each, the robot put back where it was."
  (let* ((robot (robot))
         (w (btr:world-handle (btr:world robot))) (h (btr:object-handle robot))
         (now (urdf-proj::robot-state-vectors robot))
         (b0 (btr::vector->pose (car before))) (b1 (btr::vector->pose (car after)))
         (n (length (cdr before)))
         (indices (let ((v (make-array n :element-type '(signed-byte 32)))) (dotimes (i n v) (setf (aref v i) i))))
         (q (make-array n :element-type 'double-float)))
    (unwind-protect
         (loop for k from 0 to 16
               for f = (/ k 16d0)
               collect (progn
                         (dotimes (i n) (setf (aref q i) (+ (aref (cdr before) i) (* f (- (aref (cdr after) i) (aref (cdr before) i))))))
                         (cram-native:set-object-pose
                          w h (btr::pose->vector
                               (cl-transforms:make-pose
                                (cl-transforms:v+ (cl-transforms:origin b0)
                                                  (cl-transforms:v* (cl-transforms:v- (cl-transforms:origin b1) (cl-transforms:origin b0)) f))
                                (cl-transforms:slerp (cl-transforms:orientation b0) (cl-transforms:orientation b1) f))))
                         (cram-native:set-robot-joints w h indices q)
                         (moving-frame-xyz robot sweep)))
      (urdf-proj::restore-robot-state robot now))))

(defun same-path-p (a b)
  (and (= (length a) (length b) 17)
       (every (lambda (p q) (every (lambda (x y) (< (abs (- x y)) 1d-9)) p q)) a b)))

(test sweep-paths-are-the-motions
  ;; a sweep's path, computed natively without moving the robot, holds the points that moving
  ;; the robot through the motion gives: links and carried objects, an arm motion and a base turn
  (with-open-world ()
    (board-below-the-reach-and-stick)
    (let* ((park (urdf-proj::robot-state-vectors (robot)))
           (out (progn (set-right-arm *right-out*) (urdf-proj::robot-state-vectors (robot))))
           ;; a post on the circle of the stretched-out hand, 1.2 rad on from it
           (post (let* ((hand (point-on-link "r_gripper_palm_link" 0.1))
                        (r (sqrt (+ (expt (cl-transforms:x hand) 2) (expt (cl-transforms:y hand) 2))))
                        (a (+ (atan (cl-transforms:y hand) (cl-transforms:x hand)) 1.2)))
                   (add-box 'post (cl-transforms:make-3d-vector (* r (cos a)) (* r (sin a)) 0.5) '(0.08 0.08 1.0))))
           (arm (urdf-proj:robot-sweeps park "moving-arm-joints" :arm))
           ;; the base turning by 2.5 rad with the arm out, through the post
           (turned (urdf-proj::base-state out 0d0 0d0 2.5d0))
           (turn (urdf-proj:robot-sweeps out "going" :base :after turned)))
      (is (find 'stick arm :key #'urdf-proj:sweep-moving))
      (is (find-if #'urdf-proj:sweep-moving-link arm))
      (is (not (null post)))
      (is (find 'post turn :key #'urdf-proj:sweep-hit))
      (dolist (s arm)
        (is (same-path-p (moved-frame-path s park out) (urdf-proj:sweep-path s))))
      (dolist (s turn)
        (is (same-path-p (moved-frame-path s out turned) (urdf-proj:sweep-path s))))
      ;; the robot was not moved
      (is (urdf-proj::same-state-p out (urdf-proj::robot-state-vectors (robot)))))))

(test base-turn-with-an-outstretched-arm-only-warns
  (with-open-world ()
    (set-right-arm *right-out*)
    ;; a post that the stretched-out hand meets when the base turns 90 degrees to the right
    (let* ((hand (point-on-link "r_gripper_palm_link" 0.1))
           (r (sqrt (+ (expt (cl-transforms:x hand) 2) (expt (cl-transforms:y hand) 2))))
           (a (- (atan (cl-transforms:y hand) (cl-transforms:x hand)) 0.6)))
      (add-box 'post (cl-transforms:make-3d-vector (* r (cos a)) (* r (sin a)) 0.5) '(0.08 0.08 1.0)))
    (is (null (urdf-proj:robot-collisions)))
    (setf urdf-proj:*sweep-check* :fail)
    (let ((goal (cl-transforms:make-pose (cl-transforms:make-3d-vector 0 0 0)
                                         (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) (/ pi -2)))))
      (multiple-value-bind (sweeps outcome) (recorded-sweeps (lambda () (urdf-proj:drive goal)))
        (is (eq :ok outcome))
        (is (plusp (length sweeps)))
        (is (every (lambda (s) (and (eq :base (urdf-proj:sweep-kind s)) (eq 'post (urdf-proj:sweep-hit s)))) sweeps))
        (is (< 0.1 (urdf-proj:sweep-fraction (first sweeps)) 0.6))
        (is (< (abs (- (cl-transforms:get-yaw (cl-transforms:orientation (btr:pose (robot)))) (/ pi -2))) 1d-6))))))

(test arc-past-a-post-that-a-straight-line-check-misses
  ;; the shoulder pan turns the stretched-out arm through 1.6 rad; a post stands near the
  ;; outermost point of the hand's arc, off the straight line between its two end positions
  (with-open-world ()
    (let* ((q0 (cons -1.6d0 (rest *right-out*))) (q1 (cons 0.0d0 (rest *right-out*)))
           (mid (cons -0.8d0 (rest *right-out*))))
      (set-right-arm q0)
      (let ((p0 (point-on-link "r_gripper_palm_link" 0.1)))
        (set-right-arm q1)
        (let ((p1 (point-on-link "r_gripper_palm_link" 0.1)))
          (set-right-arm mid)
          (let* ((pm (point-on-link "r_gripper_palm_link" 0.1))
                 (chord (cl-transforms:v* (cl-transforms:v+ p0 p1) 0.5)))
            ;; the arc's middle lies well outside the chord's
            (is (> (cl-transforms:v-dist pm chord) 0.15))
            (add-box 'post pm '(0.04 0.04 0.04))
            (set-right-arm q0)
            ;; a straight-line check: the palm point moving on the chord stays clear of the post
            (is (loop for k from 0 to 100
                      for f = (/ k 100d0)
                      for p = (cl-transforms:v+ p0 (cl-transforms:v* (cl-transforms:v- p1 p0) f))
                      always (> (cl-transforms:v-dist p pm) 0.1)))
            (let* ((w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot)))
                   (base (cram-native:object-pose w r)) (a (cram-native:robot-joints w r)))
              (set-right-arm q1)
              (let ((hits (cram-native:robot-sweep-check w r base a base (cram-native:robot-joints w r)
                                                         :max-step 2d0)))
                (is (plusp (length hits)))
                (is (< 0.3 (fifth (first hits)) 0.7))))))))))

(test clear-reach-near-the-table-reports-nothing
  ;; seed 000's plan in the kitchen, under :FAIL: it reaches over the table, grasps, lifts and
  ;; places the bottle, and no motion's path hits anything
  (let ((btr:*current-bullet-world* btr:*current-bullet-world*)
        (urdf-proj:*sweep-check* :fail)
        (cpl:*log-stream* (make-broadcast-stream)))
    (btw-tut:init-projection)
    (multiple-value-bind (sweeps outcome) (recorded-sweeps (lambda () (btw-tut:move-bottle)))
      (is (eq :ok outcome))
      (is (null sweeps) "sweeps: ~{~a~^; ~}" (mapcar #'urdf-proj:sweep-description sweeps)))))

(test sweeps-in-the-task-tree-and-the-replay
  (with-open-world ()
    (add-board)
    (setf urdf-proj:*sweep-check* :warn)
    (let ((cpl:*log-stream* (make-broadcast-stream))
          (cram-viewer:*record-runs* t))
      (cpl:top-level
        (cpl:with-task-tree-node (:motion "moving-arm-joints")
          (urdf-proj:move-joints nil *right-out*))))
    (let ((nodes (cpl:find-task-tree-nodes (lambda (n) (eq :sweep (cpl:node-kind n))))))
      (is (= 1 (length nodes)))
      (is (search "board" (cpl:node-designator (first nodes))))
      (is (search "\"sweep\"" (cpl:task-tree-to-json))))
    ;; the replay's step of the motion holds the sweeps: path, first contact and fraction
    (let* ((run (cram-viewer::last-run))
           (step (aref (cram-viewer:run-steps run) (1- (length (cram-viewer:run-steps run)))))
           (sweeps (remove-if-not (lambda (o) (equal "sweep" (gethash "type" o))) (cram-viewer::step-overlays step))))
      (is (plusp (length sweeps)))
      (dolist (o (mapcar #'cram-viewer::overlay-json sweeps))
        (is (= 17 (length (gethash "path" o))))
        (is (= 3 (length (gethash "point" o))))
        (is (< 0 (gethash "fraction" o) 1))
        (is (search "board" (gethash "hit" o))))
      (let ((json (cram-viewer::json-string (cram-viewer::run-json run))))
        (is (search "\"type\":\"sweep\"" json))
        (is (search "\"fraction\"" json))))))

;; ---- contacts arrived at on purpose

(defun sweep-pairs (sweeps)
  (mapcar (lambda (s) (list (urdf-proj:sweep-moving s) (urdf-proj:sweep-moving-link s)
                            (urdf-proj:sweep-hit s) (urdf-proj:sweep-hit-link s) (urdf-proj:sweep-fraction s)))
          sweeps))

(defun sweeps-with-arrivals-forced (before value)
  "ROBOT-SWEEPS from BEFORE to now with ARRIVAL-CANDIDATE-P answering VALUE (:ALWAYS: true,
:NEVER: false) instead of looking at the records."
  (sb-int:encapsulate 'urdf-proj::arrival-candidate-p 'forced
                      (lambda (f &rest args) (declare (ignore f args)) (eq value :always)))
  (unwind-protect (sweep-pairs (urdf-proj:robot-sweeps before "test" :arm))
    (sb-int:unencapsulate 'urdf-proj::arrival-candidate-p 'forced)))

(test arrivals-are-looked-up-only-where-a-record-may-be-one
  ;; the right hand passes a board and ends at a cup (an item it arrives at on purpose), with and
  ;; without a carried stick, and seeded random moves: the sweeps reported are those found when
  ;; the contacts at the end are always looked up
  (with-open-world ()
    (setf urdf-proj:*sweep-check* :warn)
    (add-board)
    (set-right-arm *right-out*)
    (add-box 'cup (point-on-link "r_gripper_palm_link" 0.12) '(0.06 0.06 0.1))
    (is (robot-touches 'cup))
    (set-right-arm *right-park*)
    (let ((before (urdf-proj::robot-state-vectors (robot))))
      (set-right-arm *right-out*)
      (let ((fast (sweep-pairs (urdf-proj:robot-sweeps before "test" :arm))))
        (is (equal (sweeps-with-arrivals-forced before :always) fast))
        ;; the hand reaches the cup on the way, and arriving at it is not reported
        (is (find 'cup (sweeps-with-arrivals-forced before :never) :key #'third))
        (is (not (find 'cup fast :key #'third)))
        (is (find 'board fast :key #'third))))
    (let ((state (sb-ext:seed-random-state 9)) (moves 0))
      (dolist (carry '(nil t))
        (when carry
          (set-right-arm *right-park*)
          (hold-stick))
        (dotimes (k 12)
          (let ((before (urdf-proj::robot-state-vectors (robot))))
            (set-right-arm (if (evenp k) *right-out* (random-arm state)))
            (let ((fast (sweep-pairs (urdf-proj:robot-sweeps before "test" :arm))))
              (when fast (incf moves))
              (is (equal (sweeps-with-arrivals-forced before :always) fast))))))
      (is (< 4 moves) "only ~d moves reported sweeps" moves))))

;; the paths as the belief state gives them: the robot set to each step through BTR, each
;; moving frame read as a pose
(defun reference-paths (before after sweeps)
  (let* ((robot (robot)) (now (urdf-proj::robot-state-vectors robot))
         (b0 (btr::vector->pose (car before))) (b1 (btr::vector->pose (car after)))
         (joints (btr:joint-names robot)))
    (unwind-protect
         (loop for k from 0 to 16
               for f = (/ k 16d0)
               collect (progn
                         (setf (btr:pose robot)
                               (cl-transforms:make-pose
                                (cl-transforms:v+ (cl-transforms:origin b0)
                                                  (cl-transforms:v* (cl-transforms:v- (cl-transforms:origin b1)
                                                                                      (cl-transforms:origin b0))
                                                                    f))
                                (cl-transforms:slerp (cl-transforms:orientation b0) (cl-transforms:orientation b1) f)))
                         (btr:set-robot-state-from-joints
                          (loop for j in joints
                                for i = (btr:joint-index robot j)
                                collect (list j (+ (aref (cdr before) i)
                                                   (* f (- (aref (cdr after) i) (aref (cdr before) i))))))
                          robot)
                         (mapcar (lambda (s)
                                   (moving-frame-xyz robot s))
                                 sweeps)))
      (urdf-proj::restore-robot-state robot now))))

(test sweep-paths-are-the-moving-frames-along-the-motion
  ;; a base move with a turn and an arm move, a link and a carried object: the same numbers as
  ;; setting the robot to each step and reading the frames, and the robot left where it was
  (with-open-world ()
    (set-right-arm *right-park*)
    (hold-stick)
    (let* ((before (urdf-proj::robot-state-vectors (robot)))
           (after (progn (set-right-arm *right-out*)
                         (setf (btr:pose (robot)) (cl-transforms:make-pose
                                                   (cl-transforms:make-3d-vector 0.3 -0.2 0)
                                                   (cl-transforms:axis-angle->quaternion
                                                    (cl-transforms:make-3d-vector 0 0 1) 0.7)))
                         (urdf-proj::robot-state-vectors (robot))))
           (sweeps (list (urdf-proj::make-sweep :moving :pr2 :moving-link "r_forearm_link")
                         (urdf-proj::make-sweep :moving 'stick)
                         (urdf-proj::make-sweep :moving :pr2 :moving-link "r_gripper_palm_link")))
           (expected (reference-paths before after sweeps)))
      (urdf-proj::note-sweep-paths (robot) before after sweeps)
      (is (urdf-proj::same-state-p after (urdf-proj::robot-state-vectors (robot))))
      (loop for s in sweeps for i from 0
            do (is (same-path-p (mapcar (lambda (step) (nth i step)) expected) (urdf-proj:sweep-path s))
                   "path of ~a" (or (urdf-proj:sweep-moving-link s) (urdf-proj:sweep-moving s))))
      ;; the stick moves: its path is no single point
      (is (< 0.1 (cl-transforms:v-dist (apply #'cl-transforms:make-3d-vector (first (urdf-proj:sweep-path (second sweeps))))
                                       (apply #'cl-transforms:make-3d-vector (car (last (urdf-proj:sweep-path (second sweeps)))))))))))

;;; ---- a seeded corpus against dense ground truth -----------------------------------------------

(defun random-arm (state)
  (loop for j in (urdf-proj:arm-joint-names :right)
        collect (multiple-value-bind (lo hi) (btr:joint-limits (robot) j)
                  (let ((lo (or lo -3d0)) (hi (or hi 3d0)))
                    (+ lo (random (- hi lo) state))))))

(defun deepest (obstacles)
  "The smallest distance of the robot to any of OBSTACLES (objects) now."
  (let ((w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot))))
    (loop for o in obstacles
          minimize (cram-native:closest-distance w r (btr:object-handle o) :max-distance 0.5d0))))

(test random-arm-moves-against-dense-ground-truth
  (with-open-world ()
    (let* ((state (sb-ext:seed-random-state 22))
           (obstacles (loop for (name x y z sx sy sz) in '((shelf 0.55 -0.45 0.75 0.4 0.5 0.02)
                                                          (post 0.45 -0.85 0.6 0.06 0.06 1.2)
                                                          (crate 0.75 -0.2 0.45 0.25 0.25 0.25)
                                                          (lamp 0.3 -0.6 1.3 0.1 0.1 0.1))
                            collect (add-box name (cl-transforms:make-3d-vector x y z) (list sx sy sz))))
           (w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot)))
           (base (cram-native:object-pose w r))
           (floor (btr:object-handle (btr:object btr:*current-bullet-world* :floor)))
           (moves 0) (with-contact 0) (missed 0) (false-alarms 0) (samples 4000))
      (loop while (< moves 40)
            do (let ((a (random-arm state)) (b (random-arm state)))
                 (set-right-arm a)
                 (when (> (deepest obstacles) 0.002)
                   (let ((qa (cram-native:robot-joints w r)))
                     (set-right-arm b)
                     (when (> (deepest obstacles) 0.002)
                       (incf moves)
                       (let* ((qb (cram-native:robot-joints w r))
                              (found (cram-native:robot-sweep-check w r base qa base qb :ignore (list (list -1 -1 floor -1))))
                              (truth (loop for k from 0 to samples
                                           minimize (progn (set-right-arm (mix a b (/ k (float samples 1d0))))
                                                           (deepest obstacles)))))
                         (when (<= truth 0) (incf with-contact))
                         ;; a contact deeper than the tolerance must be found; nothing is
                         ;; reported that stays clear by more than the sampling's resolution
                         (when (and (< truth -0.002) (null found)) (incf missed))
                         (when (and (> truth 0.002) found) (incf false-alarms))))))))
      (is (= 0 missed))
      (is (= 0 false-alarms))
      (is (< 5 with-contact 38) "~d of ~d moves touch" with-contact moves))))

;; the PR2 at the kitchen table facing it, its right arm moved between seeded random
;; configurations: FN is called COUNT times with the move's index and a list of ends
;; (base-from joints-from base-to joints-to) for CRAM-NATIVE:ROBOT-SWEEP-CHECK, the robot standing
;; at the arm move's end: the arm move, the base turned by YAW-STEP per move with the arm still,
;; and (with TURN-WITH-ARM) both at once
(defun map-kitchen-table-moves (fn seed count yaw-step &key turn-with-arm)
  (let* ((state (sb-ext:seed-random-state seed))
         (w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot))))
    (setf (btr:pose (robot)) (cl-transforms:make-pose (cl-transforms:make-3d-vector -1.8547d0 -0.381d0 0)
                                                      (cl-transforms:axis-angle->quaternion
                                                       (cl-transforms:make-3d-vector 0 0 1) (/ pi -2))))
    (let ((base (cram-native:object-pose w r)))
      (dotimes (k count)
        (let ((qa (progn (set-right-arm (random-arm state)) (cram-native:robot-joints w r)))
              (qb (progn (set-right-arm (random-arm state)) (cram-native:robot-joints w r)))
              (turned (let ((v (copy-seq base)) (yaw (- (* yaw-step k) 3d0)))
                        (setf (aref v 3) 0d0 (aref v 4) 0d0 (aref v 5) (sin (/ yaw 2)) (aref v 6) (cos (/ yaw 2)))
                        v)))
          (funcall fn k (append (list (list base qa base qb) (list base qa turned qa))
                                (and turn-with-arm (list (list base qa turned qb))))))))))

(test contact-points-lie-on-what-is-hit
  ;; seeded right-arm moves of the PR2 at the kitchen table, each also with a base turn: the point
  ;; of every record is where the pair touches, on the body hit (within its box grown by 5 cm,
  ;; as contacts count within the shapes' margins); a point left over from another computation
  ;; (the robot's base, another candidate's contact) lies elsewhere
  (with-open-world (:kitchen t)
    (let* ((w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot)))
           (floor (btr:object-handle (btr:object btr:*current-bullet-world* :floor)))
           (records 0) (off '()))
      (map-kitchen-table-moves
       (lambda (k move)
         (declare (ignore k))
         (dolist (ends move)
           (dolist (record (apply #'cram-native:robot-sweep-check w r
                                  (append ends (list :ignore (list (list -1 -1 floor -1))))))
             (destructuring-bind (mo ml ho hl fraction point) record
               (declare (ignore mo ml fraction))
               (incf records)
               (let ((box (cram-native:object-aabb w ho hl)))
                 (unless (loop for i below 3
                               always (<= (- (aref box i) 0.05d0) (aref point i) (+ (aref box (+ i 3)) 0.05d0)))
                   (push record off)))))))
       31 150 0.04d0)
      (is (< 100 records) "~d records" records)
      (is (null off) "~d of ~d contact points off the body hit, e.g. ~s" (length off) records (subseq off 0 (min 6 (length off)))))))

(test fast-search-equals-reference-in-the-kitchen
  ;; seeded right-arm moves of the PR2 at the kitchen table, with base turns: the sweep check's
  ;; search gives the same records, to the bit, as its plain reference search (:reference t)
  (with-open-world (:kitchen t)
    (let* ((w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot)))
           (floor (btr:object-handle (btr:object btr:*current-bullet-world* :floor)))
           (records 0) (differ '()))
      (map-kitchen-table-moves
       (lambda (k move)
         (dolist (ends move)
           (let* ((keys (list :ignore (list (list -1 -1 floor -1)) :skip-start-contacts (oddp k)))
                  (fast (apply #'cram-native:robot-sweep-check w r (append ends keys)))
                  (plain (apply #'cram-native:robot-sweep-check w r (append ends keys (list :reference t)))))
             (incf records (length fast))
             (unless (equalp fast plain) (push (list fast plain) differ)))))
       41 60 0.1d0 :turn-with-arm t)
      (is (< 100 records) "~d records" records)
      (is (null differ) "~d of 180 sweeps differ from the reference search, e.g. ~s" (length differ) (first differ)))))

(test arrival-contacts-asked-for-the-records-only
  ;; the contacts a motion arrives at on purpose, looked for among the objects its records hit
  ;; only: the same answer, record by record, as looking at every contact
  (with-open-world ()
    (set-right-arm *right-out*)
    (let* ((palm (cl-transforms:origin (btr:link-pose (robot) "r_gripper_palm_link")))
           (tool (cl-transforms:origin (btr:link-pose (robot) "r_gripper_tool_frame")))
           (w btr:*current-bullet-world*))
      (add-box 'cube palm '(0.05 0.05 0.05))
      (btr:add-object w :box 'stick `((,(cl-transforms:x tool) ,(cl-transforms:y tool) ,(- (cl-transforms:z tool) 0.16)) (0 0 0 1))
                      :size '(0.02 0.02 0.3) :mass 0.1)
      (btr:attach-object (robot) 'stick :link "r_gripper_tool_frame")
      (add-box 'shelf (cl-transforms:v+ tool (cl-transforms:make-3d-vector 0 0 -0.3)) '(0.2 0.2 0.02))
      (add-box 'far (cl-transforms:make-3d-vector 2 2 0.5) '(0.1 0.1 0.1))
      (flet ((h (name) (btr:object-handle (btr:object w name)))
             (l (name) (btr:link-index (robot) name)))
        (let* ((rh (btr:object-handle (robot)))
               (records (list (list rh (l "r_gripper_palm_link") (h 'cube) -1)
                              (list rh (l "r_forearm_link") (h 'cube) -1)
                              (list rh (l "r_gripper_palm_link") (h 'far) -1)
                              (list (h 'stick) -1 (h 'shelf) -1)
                              (list (h 'stick) -1 (h 'far) -1)))
               (all (urdf-proj::arrival-contact-records w (robot)))
               (asked (urdf-proj::arrival-contact-records w (robot) records)))
          (is (member (first records) all :test #'equal))
          (is (member (fourth records) all :test #'equal))
          (dolist (r records)
            (is (eq (not (member r all :test #'equal)) (not (member r asked :test #'equal))) "~s" r)))))))

(test sweep-records-beyond-the-first-room
  ;; a check that reports more records than its first call has room for runs again with room
  ;; for all of them: the same records as with room enough at once
  (with-open-world (:kitchen t)
    (let* ((w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot)))
           (base (cram-native:object-pose w r))
           (turned (let ((v (copy-seq base)))
                     (setf (aref v 0) -1.2d0 (aref v 1) -0.4d0 (aref v 5) (sin 1.5d0) (aref v 6) (cos 1.5d0))
                     v))
           (q (progn (set-right-arm *right-out*) (cram-native:robot-joints w r)))
           (at-once (cram-native:robot-sweep-check w r base q turned q))
           (again (let ((cram-native::*sweep-record-capacity* 2))
                    (cram-native:robot-sweep-check w r base q turned q))))
      (is (< 2 (length at-once)) "~d records" (length at-once))
      (is (equalp at-once again)))))
