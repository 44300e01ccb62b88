;;;; Sweep checks of the simulated robot's motions: the robot teleports between key poses, and
;;;; what its links and carried objects pass through on the way (cn_robot_sweep_check) is
;;;; reported (*SWEEP-CHECK* :WARN), or makes the motion fail with the robot left where it
;;;; was (:FAIL). Contacts a motion is meant to make are not reported: the ones it starts
;;;; from, a hand arriving at an item, a carried object arriving at a surface, and the pairs
;;;; the plan declares (INTENDED-CONTACTS, contacts.lisp).

(in-package :cram-urdf-projection)

(export '(*sweep-check* *sweep-allowed-contacts* with-allowed-sweep-contacts *sweep-hooks*
          sweep sweep-motion sweep-kind sweep-moving sweep-moving-link sweep-hit sweep-hit-link
          sweep-fraction sweep-point sweep-path sweep-description robot-sweeps))

(defvar *sweep-check* :warn
  "What the projection does about what a motion passes through between its key poses: NIL
checks nothing; :WARN (the default: plans run as in CRAM) moves and logs one line naming the
link or carried object, what it hits and where on the way; :FAIL makes an arm, torso, gripper
or tool-frame motion whose path hits something signal MANIPULATION-POSE-UNREACHABLE with the
robot left where it was (MOVE-TCP first tries its other base and torso candidates). Base
drives only warn: a real base plans its own path around obstacles.")

(defvar *sweep-hooks* '()
  "Functions called with each SWEEP a motion's check reports (the viewer's recorder, campaign
counters), before the motion warns or fails.")

(defstruct (sweep (:constructor make-sweep))
  "One pair that a motion's path brings into contact: the moving link or carried object, what
it hits, and where on the way."
  (motion "" :type string)
  (kind :arm :type keyword)
  (moving nil)
  (moving-link nil)
  (hit nil)
  (hit-link nil)
  (fraction 0d0 :type double-float)
  (point nil)
  (%path :unset)
  ;; its path as (points offset): 17 x y z from OFFSET of the DVEC POINTS, made into SWEEP-PATH's
  ;; list when first asked for
  (path-source nil))

(setf (documentation 'sweep-motion 'function) "The label of the motion (\"moving-arm-joints\" ...)."
      (documentation 'sweep-kind 'function) "The kind of motion: :ARM, :TCP, :TORSO, :GRIPPER or :BASE."
      (documentation 'sweep-moving 'function) "The name of the robot or of the carried object that hits."
      (documentation 'sweep-moving-link 'function) "The robot link that hits (a string), NIL for a carried object."
      (documentation 'sweep-hit 'function) "The name of the object hit."
      (documentation 'sweep-hit-link 'function) "The link hit (a string) of an articulated object, or NIL."
      (documentation 'sweep-fraction 'function) "Where on the way the first contact is, 0 (start) .. 1 (end)."
      (documentation 'sweep-point 'function) "The map point (x y z) of the first contact."
)

(defun sweep-description (sweep)
  "A short text naming SWEEP's moving link or object, what it hits and where on the way."
  (format nil "~:[~(~a~)~;~:*~a~*~] through ~(~a~)~@[ (~a)~] at ~,2f of the way"
          (sweep-moving-link sweep) (sweep-moving sweep) (sweep-hit sweep) (sweep-hit-link sweep)
          (sweep-fraction sweep)))

;;; ---- robot state at the ends of a motion ------------------------------------------------------

(defun robot-state-vectors (robot)
  "ROBOT's base pose and every joint value, as (base-dvec . joints-dvec)."
  (let ((w (btr:world-handle (btr:world robot))) (h (btr:object-handle robot)))
    (cons (cram-native:object-pose w h) (cram-native:robot-joints w h))))

(defun same-doubles-or-numbers-p (a b)
  "True when the sequences A and B hold the same numbers (=); DVECs compared without generic
arithmetic, as every motion's check compares its two states."
  (if (and (typep a '(simple-array double-float (*))) (typep b '(simple-array double-float (*))))
      (same-doubles-p a b)
      (and (= (length a) (length b)) (every #'= a b))))

(defun same-state-p (a b)
  (and (same-doubles-or-numbers-p (car a) (car b)) (same-doubles-or-numbers-p (cdr a) (cdr b))))

(sb-ext:defglobal **joint-index-vectors** (make-array 0)
  "Index vectors 0 .. n-1 (IVECs) by length n, made once each: RESTORE-ROBOT-STATE sets every
joint of a robot at once.")

(defun all-joint-indices (n)
  "The IVEC 0 .. N-1 (shared, not to be modified)."
  (declare (type (integer 0 100000) n))
  (let ((table **joint-index-vectors**))
    (or (and (< n (length table)) (svref table n))
        (let ((v (make-array n :element-type '(signed-byte 32)))
              (new (replace (make-array (max (1+ n) (length table)) :initial-element nil) table)))
          (dotimes (i n) (setf (aref v i) i))
          (setf (svref new n) v
                **joint-index-vectors** new)
          v))))

(defun restore-robot-state (robot state)
  "Put ROBOT back to STATE (from ROBOT-STATE-VECTORS)."
  (let ((w (btr:world-handle (btr:world robot))) (h (btr:object-handle robot)))
    (cram-native:set-object-pose w h (car state))
    (cram-native:set-robot-joints w h (all-joint-indices (length (cdr state))) (cdr state))))

;;; ---- what a motion is meant to touch ------------------------------------------------------------

(defun object-handle-named (world name entry)
  (let ((o (btr:object world name)))
    (unless o
      (projection-error "*SWEEP-ALLOWED-CONTACTS* entry ~s names ~s, which is not an object of ~
                         the belief state." entry name))
    o))

(defun allowed-contact-records (world robot)
  "The ignore records (moving-object moving-link hit-object hit-link) of the contacts the motion
is meant to make (INTENDED-CONTACTS: *SWEEP-ALLOWED-CONTACTS*, the grasped and placed objects)."
  (loop for entry in (intended-contacts robot)
        collect (progn
                  (unless (and (consp entry) (= (length entry) 2))
                    (projection-error "*SWEEP-ALLOWED-CONTACTS* entry ~s: expected (moving hit)." entry))
                  (destructuring-bind (moving hit) entry
                    (append
                     (cond ((eq moving t) (list -1 -1))
                           ((stringp moving)
                            (unless (btr:link-exists-p robot moving)
                              (projection-error "*SWEEP-ALLOWED-CONTACTS* entry ~s: ~s is not a link of ~s."
                                                entry moving (btr:name robot)))
                            (list (btr:object-handle robot) (btr:link-index robot moving)))
                           ((and moving (symbolp moving))
                            (list (btr:object-handle (object-handle-named world moving entry)) -1))
                           (t (projection-error "*SWEEP-ALLOWED-CONTACTS* entry ~s: moving part ~s, ~
                                                 expected a link name, an object name or T." entry moving)))
                     (cond ((eq hit t) (list -1 -1))
                           ((and hit (symbolp hit))
                            (list (btr:object-handle (object-handle-named world hit entry)) -1))
                           ((and (consp hit) (= (length hit) 2) (symbolp (first hit)) (stringp (second hit)))
                            (let ((o (object-handle-named world (first hit) entry)))
                              (list (btr:object-handle o) (btr:link-index o (second hit)))))
                           (t (projection-error "*SWEEP-ALLOWED-CONTACTS* entry ~s: hit ~s, expected an ~
                                                 object name, (object-name link-name) or T." entry hit))))))))

(defun contacts-with (world handle others)
  "The contacts (object link other other-link) of the object HANDLE with the objects OTHERS
(handles) of WORLD: those of CRAM-NATIVE:OBJECT-CONTACTS, asked of these objects only."
  (let ((w (btr:world-handle world)))
    (and others
         (loop for (a la b lb) in (cram-native:object-contacts
                                   w handle :except (loop for o in (btr:objects world)
                                                          for h = (btr:object-handle o)
                                                          unless (or (= h handle) (member h others)) collect h))
               collect (list a la b lb)))))

(defun arrival-contact-records (world robot &optional (records nil records-p))
  "Contacts the motion arrives at on purpose, as ignore records: the robot's hand links
touching items, and its carried objects touching anything. With RECORDS (sweep records), only
those that could be among them are looked for: the same answer for each of RECORDS."
  (let ((hands (all-hand-links robot))
        (rh (btr:object-handle robot))
        (arrivals '()))
    (flet ((hit-objects (a test)
             ;; the objects RECORDS hit with A's links that pass TEST, or all objects but the robot
             (if records-p
                 (remove-duplicates (loop for (ra la rb) in records
                                          when (and (= ra a) (funcall test la rb)) collect rb))
                 (loop for o in (btr:objects world)
                       for h = (btr:object-handle o)
                       unless (= h a) collect h))))
      (loop for (a la b lb) in (contacts-with world rh
                                              (hit-objects rh (lambda (la b)
                                                                (and (>= la 0) (typep (btr::object-by-handle world b) 'btr:item)))))
            for other = (btr::object-by-handle world b)
            when (and (= a rh) (>= la 0) (typep other 'btr:item)
                      (member (btr::link-name-of robot la) hands :test #'string=))
              do (push (list a la b lb) arrivals))
      (dolist (entry (btr:attached-objects robot))
        (let ((o (btr:object world (first entry))))
          (when o
            (let ((oh (btr:object-handle o)))
              (loop for (a la b lb) in (contacts-with world oh (remove rh (hit-objects oh (constantly t))))
                    unless (= b rh) do (push (list a la b lb) arrivals)))))))
    arrivals))

(defun arrival-candidate-p (world robot records)
  "True when one of the sweep RECORDS (moving-object moving-link hit-object hit-link ...) could
be a contact the motion arrives at on purpose (ARRIVAL-CONTACT-RECORDS): one of a carried
object, or of a hand link of ROBOT with an item. Otherwise the contacts at the end need not be
looked up."
  (let ((rh (btr:object-handle robot)) (hands :unknown))
    (loop for (mo ml ho) in records
          thereis (or (/= mo rh)
                      (and (>= ml 0)
                           (typep (btr::object-by-handle world ho) 'btr:item)
                           (member (btr::link-name-of robot ml)
                                   (if (eq hands :unknown) (setf hands (all-hand-links robot)) hands)
                                   :test #'string=))))))

(defun ignore-link-records (robot links)
  (let ((rh (btr:object-handle robot)))
    (loop for l in links
          when (btr:link-exists-p robot l) collect (list rh (btr:link-index robot l) -1 -1))))

(defun floor-records (world)
  "Ignore records of the static planes: the floor counts for no motion, as for ROBOT-COLLISIONS."
  (loop for o in (btr:objects world)
        when (eq (btr:object-kind o) :static-plane) collect (list -1 -1 (btr:object-handle o) -1)))

(defun attached-records (robot)
  (loop for entry in (btr:attached-objects robot)
        for o = (btr:object (btr:world robot) (first entry))
        when o collect (list (btr:object-handle o) -1 -1 -1)))

;;; ---- the check -------------------------------------------------------------------------------------

(defun sweep-from-record (world robot label kind record)
  (destructuring-bind (mo ml ho hl fraction point) record
    (let ((moving (btr::object-by-handle world mo)) (hit (btr::object-by-handle world ho)))
      (make-sweep :motion (string label) :kind kind
                  :moving (if moving (btr:name moving) mo)
                  :moving-link (and moving (eq moving robot) (btr::link-name-of robot ml))
                  :hit (if hit (btr:name hit) ho)
                  :hit-link (and hit (btr::link-name-of hit hl))
                  :fraction fraction :point (coerce point 'list)))))

(defun sweep-path (sweep)
  "Map points (x y z) of SWEEP's moving link or object's frame along the motion, 0 .. 1 in 16
steps."
  (when (eq (sweep-%path sweep) :unset)
    (setf (sweep-%path sweep)
          (destructuring-bind (&optional points (offset 0)) (sweep-path-source sweep)
            (and points
                 (loop for k from 0 to 16
                       for i = (+ offset (* 3 k))
                       collect (list (aref points i) (aref points (+ i 1)) (aref points (+ i 2))))))))
  (sweep-%path sweep))

(defun (setf sweep-path) (path sweep)
  "Set SWEEP's path (see SWEEP-PATH)."
  (setf (sweep-%path sweep) path))

(defun note-sweep-paths (robot before after sweeps)
  "Give each of SWEEPS its path (SWEEP-PATH): where its moving frame is along ROBOT's motion
from BEFORE to AFTER (robot states) as the sweep check moves it, the robot left where it is.
Returns SWEEPS."
  (let* ((world (btr:world robot)) (rh (btr:object-handle robot))
         (points (cram-native:robot-sweep-paths
                  (btr:world-handle world) rh (car before) (cdr before) (car after) (cdr after)
                  (mapcar (lambda (s)
                            (if (sweep-moving-link s)
                                (list rh (btr:link-index robot (sweep-moving-link s)))
                                (list (btr:object-handle (btr:object world (sweep-moving s))) -1)))
                          sweeps))))
    (loop for s in sweeps for i from 0
          do (setf (sweep-path-source s) (list points (* i 3 17))))
    sweeps))

(defun robot-sweeps (before label kind &key (robot (robot-object)) ignore-links ignore-attached
                                            (after (robot-state-vectors robot)))
  "The SWEEPs of ROBOT's motion LABEL (of KIND) from the state BEFORE (ROBOT-STATE-VECTORS) to
AFTER (default: where it is now), leaving out the contacts it starts from, arrives at on
purpose, those of IGNORE-LINKS (link names) and, with IGNORE-ATTACHED, of its carried objects,
and *SWEEP-ALLOWED-CONTACTS*. NIL when *SWEEP-CHECK* is NIL or the robot did not move."
  (unless (member *sweep-check* '(nil :warn :fail))
    (projection-error "URDF-PROJ:*SWEEP-CHECK* is ~s, expected NIL, :WARN or :FAIL." *sweep-check*))
  (when *sweep-check*
    (unless (same-state-p before after)
        (let* ((world (btr:world robot))
               (ignore (append (allowed-contact-records world robot)
                               (floor-records world)
                               (ignore-link-records robot ignore-links)
                               (and ignore-attached (attached-records robot))))
               (records (cram-native:robot-sweep-check (btr:world-handle world) (btr:object-handle robot)
                                                  (car before) (cdr before) (car after) (cdr after)
                                                  :ignore ignore :skip-start-contacts t)))
          ;; pairs are independent: the contacts arrived at on purpose (where the robot now is,
          ;; the end of the motion) are taken out afterwards
          (when (and records (arrival-candidate-p world robot records)
                     (same-state-p after (robot-state-vectors robot)))
            (let ((arrivals (arrival-contact-records world robot records)))
              (setf records (remove-if (lambda (r) (member (subseq r 0 4) arrivals :test #'equal))
                                       records))))
          (when records
            (note-sweep-paths robot before after
                              (mapcar (lambda (r) (sweep-from-record world robot label kind r))
                                      records)))))))

(defun sweeps-text (sweeps)
  (format nil "~a~@[ (and ~d more)~]" (sweep-description (first sweeps))
          (and (rest sweeps) (length (rest sweeps)))))

(defun report-sweeps (sweeps &key (robot (robot-object)) before)
  "Act on SWEEPS of one motion by *SWEEP-CHECK*: call *SWEEP-HOOKS*, note them in the task
tree, then log one warning, or (:FAIL, not a base drive) put ROBOT back to the state BEFORE and
signal MANIPULATION-POSE-UNREACHABLE naming the link or object, what it hits and where."
  (when sweeps
    (dolist (s sweeps) (dolist (hook *sweep-hooks*) (funcall hook s)))
    (let* ((first (first sweeps))
           (text (format nil "The path of ~a sweeps ~a." (sweep-motion first) (sweeps-text sweeps)))
           (fail (and (eq *sweep-check* :fail) (not (eq (sweep-kind first) :base)) before)))
      (cpl:with-task-tree-node (:sweep (format nil "~a sweeps ~(~a~)" (or (sweep-moving-link first)
                                                                          (string-downcase (string (sweep-moving first))))
                                                (sweep-hit first))
                                :designator text)
        (cond (fail
               (restore-robot-state robot before)
               (cpl:fail 'common-fail:manipulation-pose-unreachable :description text))
              (t (cpl:log-message :warn '(urdf-proj sweep) "~a" text)))))
    sweeps))

(defun base-state (state x y yaw)
  "STATE (ROBOT-STATE-VECTORS) with the base at X Y (its height kept), upright, turned to YAW."
  (let ((b (copy-seq (car state))))
    (setf (aref b 0) (float x 1d0) (aref b 1) (float y 1d0)
          (aref b 3) 0d0 (aref b 4) 0d0 (aref b 5) (sin (/ yaw 2)) (aref b 6) (cos (/ yaw 2)))
    (cons b (cdr state))))

(defun wrap-angle (a) (atan (sin a) (cos a)))

(defun state-yaw (state)
  (let ((b (car state)))
    (cl-transforms:get-yaw (cl-transforms:make-quaternion (aref b 3) (aref b 4) (aref b 5) (aref b 6)))))

(defun base-drive-sweeps (before robot)
  "The SWEEPs of a base drive from BEFORE to where ROBOT is now, driven as a base does in
place of what it cannot see: turn on the spot towards the goal, drive there (the base's own
planner finds a way around obstacles for the robot's footprint: not checked), turn on the spot
to the goal's heading. The two turns are checked, with the arms and carried objects as they are."
  (let* ((after (robot-state-vectors robot))
         (x0 (aref (car before) 0)) (y0 (aref (car before) 1))
         (x1 (aref (car after) 0)) (y1 (aref (car after) 1))
         (yaw0 (state-yaw before)) (yaw1 (state-yaw after))
         (heading (if (< (+ (expt (- x1 x0) 2) (expt (- y1 y0) 2)) 1d-4)
                      yaw0
                      (let ((h (atan (- y1 y0) (- x1 x0))))
                        ;; driving backwards when that needs less turning
                        (flet ((turn (a b) (abs (wrap-angle (- a b)))))
                          (if (< (+ (turn h yaw0) (turn h yaw1))
                                 (+ (turn (+ h pi) yaw0) (turn (+ h pi) yaw1)))
                              h (+ h pi))))))
         (heading-at-start (+ yaw0 (wrap-angle (- heading yaw0))))
         (heading-at-goal (+ yaw1 (wrap-angle (- heading yaw1)))))
    (append (robot-sweeps (base-state before x0 y0 yaw0) "going (turning at the start)" :base
                          :robot robot :after (base-state before x0 y0 heading-at-start))
            (robot-sweeps (base-state after x1 y1 heading-at-goal) "going (turning at the goal)" :base
                          :robot robot :after (base-state after x1 y1 yaw1)))))

(defun check-motion-sweep (before label kind &key (robot (robot-object)) ignore-links ignore-attached)
  "Check the motion LABEL of KIND that moved ROBOT from BEFORE (ROBOT-STATE-VECTORS) to where it
is, and act on what its path hits (REPORT-SWEEPS). Base drives (KIND :BASE) check their turns
(BASE-DRIVE-SWEEPS)."
  (when *sweep-check*
    (report-sweeps (if (eq kind :base)
                       (base-drive-sweeps before robot)
                       (robot-sweeps before label kind :robot robot :ignore-links ignore-links
                                                       :ignore-attached ignore-attached))
                   :robot robot :before before)))

(defmacro with-sweep-check ((label kind &key (robot '(robot-object))) &body body)
  "Run BODY, which moves the robot, then check the sweep of the motion LABEL of KIND from the
state before BODY to the state after it (CHECK-MOTION-SWEEP). Returns BODY's values."
  (let ((r (gensym "ROBOT")) (before (gensym "BEFORE")))
    `(let* ((,r ,robot) (,before (and *sweep-check* (robot-state-vectors ,r))))
       (multiple-value-prog1 (progn ,@body)
         (when ,before (check-motion-sweep ,before ,label ,kind :robot ,r))))))

(defun tcp-collision-mode-links (collision-mode arms robot)
  "The links whose sweeps COLLISION-MODE allows (as it allows their contacts at the goal), and
whether it allows the carried objects' ones: (values links attached-p everything-p)."
  (case collision-mode
    (:allow-all (values nil t t))
    ((:allow-hand :allow-fingers) (values (loop for arm in arms append (hand-links arm robot)) nil nil))
    (:allow-attached (values (loop for arm in arms append (hand-links arm robot)) t nil))
    (:allow-arm (values (loop for arm in arms append (append (hand-links arm robot)
                                                             (ignore-errors (rob-int:get-arm-links (robot-name) arm))))
                        nil nil))
    (t (values nil nil nil))))

(defun tcp-sweep-verdict (before collision-mode arms robot)
  "Whether MOVE-TCP may keep its candidate state ROBOT is in, reached from BEFORE
(ROBOT-STATE-VECTORS, NIL: no check), as far as its path goes: (values acceptable-p sweeps).
COLLISION-MODE allows the sweeps of the links and objects it allows to touch at the goal.
Under :WARN the sweeps are reported here and the candidate is kept; under :FAIL a candidate
with sweeps is not acceptable."
  (if (null before)
      (values t nil)
      (multiple-value-bind (links attached everything) (tcp-collision-mode-links collision-mode arms robot)
        (let ((sweeps (and (not everything)
                           (robot-sweeps before "moving-tcp" :tcp :robot robot :ignore-links links
                                                                   :ignore-attached attached))))
          (cond ((null sweeps) (values t nil))
                ((eq *sweep-check* :fail) (values nil sweeps))
                (t (report-sweeps sweeps :robot robot) (values t sweeps)))))))

;; plans run their motions in task threads: bindings made around a plan reach them
(dolist (symbol '(*sweep-check* *sweep-allowed-contacts* *sweep-hooks*))
  (pushnew symbol cpl:*inherited-specials*))
