;;;; MOVE-TCP: reach tool-frame poses with IK per arm, trying base offsets and torso heights,
;;;; every candidate checked for collisions in the belief state.

(in-package :cram-urdf-projection)

(defparameter *base-offsets* '(0d0 -0.1d0 0.1d0 -0.2d0 0.2d0)
  "Base x and y offsets (metres, base frame) MOVE-TCP tries, 0 first then by size.")

(defparameter *torso-step* 0.1d0 "Step (metres or radians) of the torso values MOVE-TCP tries.")

(defparameter *reach-ik-restarts* 8
  "Random restarts of each IK call MOVE-TCP makes for a candidate base offset and torso value,
after the attempt from the arm's joints as they are.")

(defparameter *collision-modes* '(nil :avoid-all :allow-all :allow-hand :allow-fingers :allow-arm
                                  :allow-attached)
  "The collision modes of MOVE-TCP.")

(defun arm-ik-chain (arm &optional (robot (robot-object)))
  "The IK chain of ARM: from the parent link of its first arm joint (the torso) to the child
link of its last arm joint (the wrist)."
  (let ((generation (prolog:database-generation))
        (urdf (btr:urdf robot))
        (name (robot-name)))
    (or (loop for (g u n a . chain) in *arm-ik-chains*
              when (and (eql g generation) (eq u urdf) (equal n name) (eq a arm))
                return chain)
        (let ((chain (find-arm-ik-chain arm robot)))
          ;; the answer depends on the ARM and ARM-JOINTS facts and the URDF alone
          (when (and (plain-facts-p 'rob-int:arm) (plain-facts-p 'rob-int:arm-joints))
            (setf *arm-ik-chains*
                  (cons (list* generation urdf name arm chain)
                        (remove generation *arm-ik-chains* :key #'car :test-not #'eql))))
          chain))))

(defun find-arm-ik-chain (arm robot)
  (let* ((joints (cl-urdf:joints (btr:urdf robot)))
         (names (arm-joint-names arm))
         (first-joint (gethash (first names) joints))
         (last-joint (gethash (car (last names)) joints)))
    (unless (and first-joint last-joint)
      (projection-error "Arm ~s joints ~s are not joints of ~s." arm names (btr:name robot)))
    (ik-chain robot (cl-urdf:name (cl-urdf:parent first-joint)) (cl-urdf:name (cl-urdf:child last-joint)))))

(defun arm-ik (arm ee-map-pose &key (robot (robot-object)) seed (max-restarts *ik-max-restarts*))
  "Joint values (ARM-JOINTS order) putting the end-effector link of ARM at EE-MAP-POSE (map)
for the robot's current base pose and torso, or NIL. Quick distance check before solving."
  (let ((chain (arm-ik-chain arm robot)))
    (chain-ik-from-map chain (end-effector-link arm) (first-joint-child chain robot) ee-map-pose
                       robot seed max-restarts)))

(defun first-joint-child (chain robot)
  "The child link of the first joint of CHAIN, a chain of ROBOT."
  (let ((joint (svref (ik-chain-joint-names chain) 0)))
    (cl-urdf:name (cl-urdf:child (or (gethash joint (cl-urdf:joints (btr:urdf robot)))
                                     (projection-error "Joint ~s is not a joint of ~s." joint
                                                       (btr:name robot)))))))

(defun beyond-chain-reach-p (chain first-child point robot)
  "True when the map POINT is farther from the origin of ROBOT's link FIRST-CHILD (the child of
CHAIN's first joint) than the chain reaches, with 5 cm to spare."
  (let* ((index (or (robot-link-index robot first-child)
                    (projection-error "Link ~s is not a link of ~s." first-child (btr:name robot))))
         (origin (cram-native:robot-link-pose (btr::whandle robot) (btr:object-handle robot) index))
         (limit (+ (ik-chain-reach chain) 0.05d0)))
    (declare (type (simple-array double-float (*)) origin) (type double-float limit))
    (let ((dx (- (aref origin 0) (float (cl-transforms:x point) 1d0)))
          (dy (- (aref origin 1) (float (cl-transforms:y point) 1d0)))
          (dz (- (aref origin 2) (float (cl-transforms:z point) 1d0))))
      (> (+ (* dx dx) (* dy dy) (* dz dz)) (* limit limit)))))

(defun chain-ik-goal (chain ee first-child ee-map-pose robot)
  "The goal of CHAIN's tip (a pose in the chain's base link frame) that puts ROBOT's
end-effector link EE at EE-MAP-POSE, or NIL when the goal lies beyond the chain's reach from
the child link of its first joint FIRST-CHILD (quick checks, before anything is solved)."
  (when (and (string= ee (ik-chain-tip-link chain))
             (beyond-chain-reach-p chain first-child (cl-transforms:origin ee-map-pose) robot))
    ;; the quick distance check before anything else is computed
    (return-from chain-ik-goal nil))
  (let* ((base-pose (btr:link-pose robot (ik-chain-base-link chain)))
         ;; the chain ends at the wrist; the end-effector link is the wrist or hangs below it
         (tip (ik-chain-tip-link chain))
         (tip-goal (if (string= ee tip)
                       (cl-transforms:pose->transform ee-map-pose)
                       (cl-transforms:transform* (cl-transforms:pose->transform ee-map-pose)
                                                 (relative-transform (btr:link-pose robot ee)
                                                                     (btr:link-pose robot tip)))))
         (first-joint-origin (cl-transforms:origin (btr:link-pose robot first-child))))
    (unless (> (cl-transforms:v-dist first-joint-origin (cl-transforms:translation tip-goal))
               (+ (ik-chain-reach chain) 0.05d0))
      (cl-transforms:transform->pose
       (cl-transforms:transform* (cl-transforms:transform-inv (cl-transforms:pose->transform base-pose))
                                 tip-goal)))))

(defun chain-joint-values (chain robot joints)
  "The values of CHAIN's joints, in its order, read from JOINTS: every joint value of ROBOT in
index order (CRAM-NATIVE:ROBOT-JOINTS)."
  (declare (type (simple-array double-float (*)) joints))
  (map 'list (lambda (j) (aref joints (btr::joint-index robot j))) (ik-chain-joint-names chain)))

(defun chain-ik-from-map (chain ee first-child ee-map-pose robot seed max-restarts)
  "ARM-IK with what depends on the arm alone given: its CHAIN, its end-effector link EE and
the child link of the chain's first joint FIRST-CHILD."
  (let ((goal (chain-ik-goal chain ee first-child ee-map-pose robot)))
    (when goal
      (solve-ik chain goal :seed (or seed (map 'list (lambda (j) (btr:joint-state robot j))
                                               (ik-chain-joint-names chain)))
                           :max-restarts max-restarts))))

(defun check-collision-mode (mode)
  (unless (member mode *collision-modes*)
    (projection-error "Collision mode ~s: expected one of ~s." mode *collision-modes*))
  mode)

(defun perform-collision-check (collision-mode arms &optional (robot (robot-object)))
  "True when the robot's state is acceptable under COLLISION-MODE for the moving ARMS:
:ALLOW-ALL anything; NIL / :AVOID-ALL no contact of the robot with anything but its attached
objects (which may touch only the robot); the lenient modes leave out the hands, fingers, arms
or attached objects when *BE-STRICT-WITH-COLLISIONS* is true and allow everything otherwise."
  (check-collision-mode collision-mode)
  (flet ((clear-without (links) (not (robot-collides-p :robot robot :ignore-links links))))
    (case collision-mode
      ((nil :avoid-all) (clear-without nil))
      (:allow-all t)
      (t (or (not *be-strict-with-collisions*)
             (clear-without
              (loop for arm in arms
                    append (ecase collision-mode
                             ((:allow-hand :allow-attached) (hand-links arm robot))
                             (:allow-fingers
                              (remove-if-not (lambda (l) (fact-value '?l `(rob-int:hand-finger-link ,(robot-name) ,arm ,l)))
                                             (hand-links arm robot)))
                             (:allow-arm (append (hand-links arm robot)
                                                 (rob-int:get-arm-links (robot-name) arm)))))))))))

(defvar *torso-candidates* nil
  "NIL, or #(urdf joint value step candidates): the last answer of TORSO-CANDIDATES, for the
URDF, the torso joint and its value and the *TORSO-STEP* it was made for (the joint's limits
are the URDF's).")

(defun torso-candidates (robot fixed-torso)
  "Torso values to try: the current one, then steps of *TORSO-STEP* within the limits by
distance. NIL when the robot has no movable torso. Not to be modified (the last answer is
given again for the same torso value and step)."
  (let ((joint (torso-joint)))
    (when (movable-joint-p robot joint)
      (let ((current (btr:joint-state robot joint)))
        (if fixed-torso
            (list current)
            (let ((last *torso-candidates*)
                  (urdf (btr:urdf robot)))
              (if (and last (eq (svref last 0) urdf) (equal (svref last 1) joint)
                       (= (svref last 2) current) (= (svref last 3) *torso-step*))
                  (svref last 4)
                  (multiple-value-bind (lo hi) (btr:joint-limits robot joint)
                    (let ((values (torso-values current lo hi)))
                      (setf *torso-candidates* (vector urdf joint current *torso-step* values))
                      values)))))))))

(defun torso-values (current lo hi)
  "The torso values of TORSO-CANDIDATES for the torso at CURRENT with the limits LO and HI."
  (let ((values (list current)))
    (loop for k from 1 to 100
          for up = (+ current (* k *torso-step*))
          for down = (- current (* k *torso-step*))
          while (or (<= up (+ hi 1d-9)) (>= down (- lo 1d-9)))
          do (when (>= down (- lo 1d-9)) (push down values))
             (when (<= up (+ hi 1d-9)) (push up values)))
    (dolist (limit (list lo hi))
      (unless (find limit values :test (lambda (a b) (< (abs (- a b)) 0.02d0)))
        (push limit values)))
    (stable-sort (nreverse values) #'< :key (lambda (v) (abs (- v current))))))

(defvar *base-candidates* (cons nil nil)
  "(offsets . candidates): the base offsets BASE-CANDIDATES sorted last, for a copy of the
*BASE-OFFSETS* they were made of.")

(defun base-candidates (move-base)
  "The (dx dy) base offsets MOVE-TCP tries, nearest first: every pair of *BASE-OFFSETS* (made
again only when *BASE-OFFSETS* changed), or only (0 0) without MOVE-BASE. Not to be modified."
  (if move-base
      (let ((cached *base-candidates*))
        (if (equal (car cached) *base-offsets*)
            (cdr cached)
            (let ((candidates
                    (stable-sort (loop for x in *base-offsets*
                                       append (loop for y in *base-offsets* collect (list x y)))
                                 #'< :key (lambda (o) (+ (expt (first o) 2) (expt (second o) 2))))))
              (setf *base-candidates* (cons (copy-list *base-offsets*) candidates))
              candidates)))
      (list (list 0d0 0d0))))

(defun offset-base-pose (pose dx dy)
  (cl-transforms:transform->pose
   (cl-transforms:transform* (cl-transforms:pose->transform pose)
                             (cl-transforms:make-transform (cl-transforms:make-3d-vector dx dy 0)
                                                           (cl-transforms:make-identity-rotation)))))

(defun tcp->ee-pose (arm tcp-map-pose robot)
  (cl-transforms:transform->pose
   (cl-transforms:transform* (cl-transforms:pose->transform tcp-map-pose)
                             (nth-value 1 (tcp-in-ee-transform arm robot)))))

(defparameter *goal-bound-penetration* 0.001d0
  "Metres a link that the tool goal fixes must reach into the world, beyond what the IK can
move it (GOAL-BOUND-SLACK), before MOVE-TCP gives the goal up at once: a margin for the
contact distances' own error.")

(defun goal-bound-slack (robot chain link position-error rotation-error)
  "How far (metres) any point of ROBOT's LINK, fixed to the tip of CHAIN, may lie from where
it is now in another IK solution of the same goal: the tip is now POSITION-ERROR metres and
ROTATION-ERROR radians off the goal and another solution within the IK tolerances, so it moves
by at most their sums, and a point at distance r from the tip (bounded by the corners of the
link's bounding box) by the position's part plus r times the rotation's."
  (let* ((tip (cl-transforms:origin (btr:link-pose robot (ik-chain-tip-link chain))))
         (tx (float (cl-transforms:x tip) 1d0))
         (ty (float (cl-transforms:y tip) 1d0))
         (tz (float (cl-transforms:z tip) 1d0))
         (box (cram-native:object-aabb (btr::whandle robot) (btr:object-handle robot)
                                       (robot-link-index robot link)))
         (r 0d0))
    (declare (type double-float tx ty tz r) (type (simple-array double-float (*)) box))
    (dotimes (k 8)
      (let ((dx (- (aref box (if (logbitp 0 k) 3 0)) tx))
            (dy (- (aref box (if (logbitp 1 k) 4 1)) ty))
            (dz (- (aref box (if (logbitp 2 k) 5 2)) tz)))
        (setf r (max r (sqrt (+ (* dx dx) (* dy dy) (* dz dz)))))))
    (+ position-error *ik-position-tolerance*
       (* r (+ rotation-error *ik-rotation-tolerance*)))))

(defun goal-bound-links (chain robot)
  "The links of ROBOT that the goal of the IK CHAIN fixes in the map: its tip link and every
link below it (the wrist, the hand, the fingers)."
  (link-descendants robot (ik-chain-tip-link chain)))

(defun goal-bound-collision-p (chains robot &optional (position-error 0d0) (rotation-error 0d0))
  "True when a link that the goals of CHAINS fix in the map (GOAL-BOUND-LINKS) reaches into
anything but the robot, its attached objects, the floor and the contacts the motion is meant
to make deeper than any other IK solution of the goals can move it (GOAL-BOUND-SLACK, from the
current solution's POSITION-ERROR and ROTATION-ERROR, plus *GOAL-BOUND-PENETRATION*): no
other base offset or torso value can free it, as the hand stays at its goal."
  (let* ((world (btr:world robot))
         (bound-links (mapcar (lambda (chain) (cons chain (goal-bound-links chain robot))) chains))
         (except (multiple-value-bind (attached attached-objects planes)
                     (collision-excepts world robot)
                   (declare (ignore attached))
                   (append planes attached-objects)))
         (intended (intended-contacts robot)))
    (flet ((chain-fixing (link)
             (car (find-if (lambda (entry) (member link (cdr entry) :test #'string=)) bound-links))))
      (loop for (nil la other-handle other-la distance)
              in (cram-native:object-contacts (btr::world-handle world) (btr:object-handle robot)
                                              :threshold (- *goal-bound-penetration*)
                                              :except (mapcar #'btr:object-handle except))
            for link = (btr::link-name-of robot la)
            for chain = (and link (chain-fixing link))
            for other = (and chain (btr::object-by-handle world other-handle))
            thereis (and other (not (eq other robot))
                         ;; the slack of a link that touches something, computed only for it
                         (< distance (- (+ (goal-bound-slack robot chain link
                                                             position-error rotation-error)
                                           *goal-bound-penetration*)))
                         (not (intended-contact-p intended robot link other
                                                  (btr::link-name-of other other-la))))))))

(defun shoulder-positions (robot ee-goals torso torsos)
  "For each value of TORSOS (NIL: the torso as it is), a list with, per goal of EE-GOALS ((arm
ee-pose chain end-effector first-child seed) ...), the map position (a 3-vector of doubles) of the
goal's FIRST-CHILD link with the joint TORSO at that value and the robot otherwise as it is,
or NIL for a goal whose end effector is not its chain's tip (not filtered). Computed without
changing the belief state."
  (let* ((world (btr::whandle robot))
         (handle (btr:object-handle robot))
         (links (mapcar (lambda (g) (robot-link-index robot (fifth g))) ee-goals))
         (tips (mapcar (lambda (g) (string= (fourth g) (ik-chain-tip-link (third g)))) ee-goals))
         (joint (and torso (some #'identity torsos) (btr::joint-index robot torso))))
    (flet ((positions (v)
             (declare (type (simple-array double-float (*)) v))
             (loop for link in links for tip in tips for i from 0
                   collect (and link tip
                                (let ((p (make-array 3 :element-type 'double-float)))
                                  (replace p v :start2 (* 7 i))
                                  p)))))
      (let ((indices (mapcar (lambda (l) (or l 0)) links)))
        (mapcar (lambda (value)
                  (positions
                   (if value
                       (multiple-value-bind (lo hi) (btr:joint-limits robot torso)
                         (cram-native:robot-link-poses-if
                          world handle (list joint)
                          (list (float (max (or lo value) (min (or hi value) value)) 1d0))
                          indices))
                       (let ((v (make-array (* 7 (length indices)) :element-type 'double-float)))
                         (loop for l in indices for i from 0
                               do (replace v (cram-native:robot-link-pose world handle l)
                                           :start1 (* 7 i)))
                         v))))
                torsos)))))

(defun base-offset-shift (base dx dy)
  "How far (a 3-vector of doubles, map) a point fixed to the robot moves when its base goes
from BASE to OFFSET-BASE-POSE BASE DX DY."
  (let ((v (cl-transforms:rotate (cl-transforms:orientation base)
                                 (cl-transforms:make-3d-vector dx dy 0))))
    (make-array 3 :element-type 'double-float
                  :initial-contents (list (float (cl-transforms:x v) 1d0)
                                          (float (cl-transforms:y v) 1d0)
                                          (float (cl-transforms:z v) 1d0)))))

(defvar *base-offset-shifts* nil
  "(orientation candidates . shifts): the last answer of BASE-OFFSET-SHIFTS, for the base
orientation (a quaternion) and the list of base candidates it was made for.")

(defun same-rotation-numbers-p (a b)
  "True when the quaternions A and B have the same four numbers."
  (and (= (cl-transforms:x a) (cl-transforms:x b)) (= (cl-transforms:y a) (cl-transforms:y b))
       (= (cl-transforms:z a) (cl-transforms:z b)) (= (cl-transforms:w a) (cl-transforms:w b))))

(defun base-offset-shifts (base candidates)
  "BASE-OFFSET-SHIFT of BASE for each (dx dy) of CANDIDATES (a list BASE-CANDIDATES gave), in
order: made again only for another base orientation or list (the searches of a pre-check all
start from the base pose it stands at). Not to be modified."
  (let ((q (cl-transforms:orientation base))
        (last *base-offset-shifts*))
    (if (and last (eq (second last) candidates) (same-rotation-numbers-p (first last) q))
        (cddr last)
        (let ((shifts (mapcar (lambda (o) (base-offset-shift base (first o) (second o))) candidates)))
          (setf *base-offset-shifts* (list* q candidates shifts))
          shifts))))

(defun goals-within-reach-p (shoulders shift ee-goals)
  "False when a goal of EE-GOALS lies farther from its shoulder (SHOULDERS, one position or
NIL per goal, moved by SHIFT) than its chain reaches, with the 5 cm to spare of
CHAIN-IK-FROM-MAP's own check; true otherwise."
  (declare (type (simple-array double-float (3)) shift))
  (loop for s in shoulders for g in ee-goals
        always (or (null s)
                   (let* ((goal (cl-transforms:origin (second g)))
                          (limit (+ (ik-chain-reach (third g)) 0.05d0))
                          (dx (- (+ (aref s 0) (aref shift 0)) (float (cl-transforms:x goal) 1d0)))
                          (dy (- (+ (aref s 1) (aref shift 1)) (float (cl-transforms:y goal) 1d0)))
                          (dz (- (+ (aref s 2) (aref shift 2)) (float (cl-transforms:z goal) 1d0))))
                     (declare (type double-float limit dx dy dz)
                              (type (simple-array double-float (*)) s))
                     (<= (+ (* dx dx) (* dy dy) (* dz dz)) (* limit limit))))))

(defparameter *pass-over-blocked-bases* t
  "When true, MOVE-TCP's search under the strict collision check, for one goal, passes over the
candidates of a base offset at which a link that only the base moves (the base, its wheels and
sensors) touches something, instead of solving their IK and finding each in collision: once
the goal is known not to be blocked at the hand (GOAL-BOUND-COLLISION-P), and with a native IK
solver (PASS-OVER-IK). The search finds what it finds without it. NIL: every candidate is
solved.")

(defvar *reach-moving-links* '()
  "REACH-MOVING-LINKS' answers, entries (urdf chain torso . link-indices).")

(defun reach-moving-links (robot chain torso)
  "The link indices of ROBOT that the candidates of REACH-TCP-POSES for the IK CHAIN move: the
links below the chain's first joint and, with a TORSO joint, below it. The other links move
only with the base."
  (let ((urdf (btr:urdf robot)))
    (or (loop for (u c j . links) in *reach-moving-links*
              when (and (eq u urdf) (eq c chain) (equal j torso)) return links)
        (let* ((torso-joint (and torso (gethash torso (cl-urdf:joints urdf))))
               (names (append (link-descendants robot (first-joint-child chain robot))
                              (and torso-joint
                                   (link-descendants robot (cl-urdf:name (cl-urdf:child torso-joint))))))
               (links (sort (remove-duplicates (remove nil (mapcar (lambda (l) (robot-link-index robot l))
                                                                    names)))
                            #'<)))
          (push (list* urdf chain torso links) *reach-moving-links*)
          (when (> (length *reach-moving-links*) 16)
            (setf *reach-moving-links* (subseq *reach-moving-links* 0 16)))
          links))))

(defun reach-tcp-poses (goals collision-mode move-base fixed-torso)
  "Bring each (arm . tcp-map-pose) of GOALS there at once. Tries base offsets and torso values
in order; the first candidate with IK solutions for every arm that passes the collision check
is kept. When the first candidate that fails the strict check (COLLISION-MODE NIL or
:AVOID-ALL) fails it with a hand at its goal touching the world (GOAL-BOUND-COLLISION-P), no
other candidate is tried. Signals MANIPULATION-POSE-UNREACHABLE (state restored) when none
passes, and MANIPULATION-GOAL-NOT-REACHED when the reached tool frames are off their goals."
  (let* ((robot (robot-object))
         (arms (mapcar #'car goals))
         ;; the base pose and every joint as they are: a search that fails puts them back
         (state0 (robot-state-vectors robot))
         ;; (arm ee-pose chain end-effector-link first-joint-child) per goal: what ARM-IK looks up
         ;; and, last, the IK seed: the arm's joints as they are, which every candidate starts
         ;; from (a candidate that fails puts them back)
         (ee-goals (mapcar (lambda (g)
                             (let* ((arm (car g)) (chain (arm-ik-chain arm robot)))
                               (list arm (tcp->ee-pose arm (cdr g) robot) chain
                                     (end-effector-link arm) (first-joint-child chain robot)
                                     (chain-joint-values chain robot (cdr state0)))))
                           goals))
         (base0 (btr:pose robot))
         (torso (torso-joint))
         (torsos (or (torso-candidates robot fixed-torso) (list nil)))
         (torso-index (and torso (some #'identity torsos) (btr::joint-index robot torso)))
         ;; what a candidate changes besides the torso, which each candidate sets itself
         (arms0 (loop for (nil nil chain nil nil seed) in ee-goals
                      append (map 'list #'list (ik-chain-joint-names chain) seed)))
         (sweep-start (and *sweep-check* state0))
         (goal-checked (not (member collision-mode '(nil :avoid-all))))
         ;; under the strict check, once a goal is known not to be hopeless: a base offset at
         ;; which a link that only the base moves touches something passes its candidates over
         ;; (as for one goal with a native solver every IK call draws one random number whatever
         ;; it finds, passed-over candidates draw it too, and the search goes on as it would)
         (fixed-links-check (and *pass-over-blocked-bases*
                                 (not goal-checked)
                                 (= (length ee-goals) 1)
                                 (ik-chain-native (third (first ee-goals)))
                                 (null *ik-fallback-restarts*)))
         (swept nil)
         (goals-key (reach-goals-key goals)))
    (block search
      ;; the state found for the same goals before, when the base may go there from here
      (let ((known (recall-reach-state robot goals-key base0
                                      (if move-base
                                          (reduce #'max (mapcar #'abs *base-offsets*)
                                                  :initial-value 0d0)
                                          0d0)
                                      torso fixed-torso)))
        (when known
          (setf (btr:pose robot) (reach-state-base known))
          (btr:set-robot-state-from-joints (reach-state-joints known) robot)
          (when (and (perform-collision-check collision-mode arms robot)
                     (multiple-value-bind (ok sweeps) (tcp-sweep-verdict sweep-start collision-mode arms robot)
                       (unless ok (setf swept sweeps))
                       ok))
            (return-from search t))
          (restore-robot-state robot state0)))
      (block candidates
        ;; where each goal's shoulder would be for each torso value: candidates whose goals
        ;; are out of the arm's reach are passed over without setting the robot's state
        (let ((shoulders (shoulder-positions robot ee-goals torso torsos)))
         (loop
          with candidates = (base-candidates move-base)
          for offset in candidates
          for shift in (base-offset-shifts base0 candidates)
          do
          (let ((placed nil)
                (base-blocked :unknown))
           (loop
            for torso-value in torsos
            for torso-shoulders in shoulders
            when (goals-within-reach-p torso-shoulders shift ee-goals)
            do
            (unless placed
              (setf (btr:pose robot) (offset-base-pose base0 (first offset) (second offset))
                    placed t))
            (when torso-value (btr::set-indexed-joint robot torso-index torso-value))
            (if (and fixed-links-check goal-checked
                     (if (eq base-blocked :unknown)
                         (setf base-blocked
                               (other-links-collide-p
                                robot (reach-moving-links robot (third (first ee-goals)) torso)))
                         base-blocked))
                (destructuring-bind (pose chain ee first-child &rest rest) (rest (first ee-goals))
                  (declare (ignore rest))
                  (when (chain-ik-goal chain ee first-child pose robot)
                    (pass-over-ik chain)))
            (let* ((position-error 0d0) (rotation-error 0d0)
                   (solutions (loop for (nil pose chain ee first-child seed) in ee-goals
                                    for (q pe re) = (multiple-value-list
                                                     (chain-ik-from-map chain ee first-child pose robot seed
                                                                        *reach-ik-restarts*))
                                    unless q do (return nil)
                                    do (setf position-error (max position-error pe)
                                             rotation-error (max rotation-error re))
                                    collect (mapcar #'list (coerce (ik-chain-joint-names chain) 'list) q))))
              (when (and solutions (= (length solutions) (length ee-goals)))
                (btr:set-robot-state-from-joints (apply #'append solutions) robot)
                (let ((clear (perform-collision-check collision-mode arms robot)))
                  (when (and clear
                             (multiple-value-bind (ok sweeps)
                                 (tcp-sweep-verdict sweep-start collision-mode arms robot)
                               (unless ok (setf swept (or swept sweeps)))
                               ok))
                    (remember-reach-state robot goals-key (btr:pose robot)
                                          (append (and torso-value (list (list torso torso-value)))
                                                  (apply #'append solutions)))
                    (return-from search t))
                  (let ((hopeless (and (not clear) (not goal-checked)
                                       (setf goal-checked t)
                                       (goal-bound-collision-p (mapcar #'third ee-goals) robot
                                                               position-error rotation-error))))
                    (btr:set-robot-state-from-joints arms0 robot)
                    (when hopeless (return-from candidates))))))))))))
      (restore-robot-state robot state0)
      (report-sweeps swept :robot robot :before sweep-start)  ; signals under :fail
      (cpl:fail 'common-fail:manipulation-pose-unreachable
                :description (lambda ()
                               (format nil "Tool frame goals ~{~{~(~a~) ~a~}~^, ~}: unreachable for ~
                                            the end effector or in collision."
                                       (mapcar (lambda (g) (list (car g) (pose-summary (cdr g))))
                                               goals)))))
    ;; final check: the tool frames are where they were asked to be
    (loop for (arm . pose) in goals
          for tool = (tool-frame arm)
          for reached = (btr:link-pose robot (if (and tool (btr:link-exists-p robot tool)) tool (end-effector-link arm)))
          for goal = (if (and tool (btr:link-exists-p robot tool)) pose (tcp->ee-pose arm pose robot))
          do (multiple-value-bind (d a) (btr::pose-distance reached goal)
               (when (or (> d (* 2 *ik-position-tolerance*)) (> a (* 2 *ik-rotation-tolerance*)))
                 (cpl:fail 'common-fail:manipulation-goal-not-reached
                           :description (format nil "The ~(~a~) tool frame ended ~,4f m and ~,4f rad away ~
                                                     from its goal." arm d a)))))
    t))

(defun pose-list (poses what)
  (cond ((null poses) nil)
        ((or (typep poses 'cl-transforms-stamped:pose-stamped) (cl-transforms:pose-p poses))
         (list (pose-in-map poses what)))
        ((listp poses)
         (if (and (= (length poses) 2) (every #'listp poses) (every #'realp (first poses)))
             (list (pose-in-map poses what))
             (mapcar (lambda (p) (pose-in-map p what)) poses)))
        (t (projection-error "~a ~s: expected a pose, a pose-stamped or a list of them." what poses))))

(defun move-tcp (left-poses right-poses &key collision-mode (move-base t) fixed-torso)
  "Move the tool frames of the arms to LEFT-POSES and RIGHT-POSES (each a pose-stamped, a map
pose, or a list of them, aligned by index; NIL: that arm stays). For each step the IK of the
wrist (tool frame converted through the TCP-IN-EE pose) is solved in the torso frame, trying
base offsets (unless MOVE-BASE is NIL) and torso values (unless FIXED-TORSO), each candidate
checked under COLLISION-MODE. Failures of all but the last step are logged and skipped; the
last step's MANIPULATION-LOW-LEVEL-FAILURE propagates."
  (check-collision-mode collision-mode)
  (let* ((lefts (pose-list left-poses "left TCP pose"))
         (rights (pose-list right-poses "right TCP pose"))
         (steps (max (length lefts) (length rights))))
    (when lefts (check-arm :left))
    (when rights (check-arm :right))
    (with-motion ("moving-tcp")
     (with-tcp-in-ee-kept
      (dotimes (i steps t)
        (let ((goals (append (let ((p (nth i lefts))) (and p (list (cons :left p))))
                             (let ((p (nth i rights))) (and p (list (cons :right p)))))))
          (when goals
            (if (= i (1- steps))
                (reach-tcp-poses goals collision-mode move-base fixed-torso)
                (handler-case (reach-tcp-poses goals collision-mode move-base fixed-torso)
                  (common-fail:manipulation-low-level-failure (failure)
                    (cpl:log-message :warn '(urdf-proj move-tcp) "Skipping intermediate pose ~d: ~a"
                                     i failure)))))))))))
