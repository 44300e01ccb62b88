;;;; cram-native: kinematic chains, forward and inverse kinematics (KDL, in process).

(in-package :cram-native)

(defcn "cn_chain_create" :int (w :int) (r :int) (base :string) (tip :string))
(defcn "cn_chain_destroy" :int (c :int))
(defcn "cn_chain_num_joints" :int (c :int))
(defcn "cn_chain_joints" :int (c :int) (out :pointer))
(defcn "cn_chain_limits" :int (c :int) (lo :pointer) (hi :pointer))
(defcn "cn_chain_fk" :int (c :int) (q :pointer) (out :pointer))
(defcn "cn_chain_may_reach" :int (c :int) (position :pointer) (pos-tol :double))
(defcn "cn_chain_reach_map_get" :int (c :int) (params :pointer) (cells :pointer) (cap :int))
(defcn "cn_chain_reach_map_set" :int (c :int) (params :pointer) (cells :pointer) (n :int))
(defcn "cn_chain_ik_memo_size" :int (c :int))
(defcn "cn_chain_ik" :int (c :int) (target :pointer) (seed :pointer) (restarts :int)
  (pos-tol :double) (rot-tol :double) (rng :unsigned-int) (out :pointer) (err :pointer))

(defun make-chain (world robot base-link tip-link)
  "A kinematic chain of ROBOT from link BASE-LINK to TIP-LINK (names); returns its handle.
It stays valid when WORLD is destroyed, until DESTROY-CHAIN."
  (ccall "cn_chain_create" world robot (string-arg base-link 'make-chain "base link")
         (string-arg tip-link 'make-chain "tip link")))

(defun destroy-chain (chain)
  "Free CHAIN."
  (ccall "cn_chain_destroy" chain)
  nil)

(defun chain-joint-count (chain)
  "Number of movable joints of CHAIN."
  (ccall "cn_chain_num_joints" chain))

(defun chain-joints (chain)
  "Robot joint indices of CHAIN's movable joints, base to tip, as a list."
  (let ((v (make-array (ccall "cn_chain_num_joints" chain) :element-type '(signed-byte 32))))
    (with-vector-pointers ((p v)) (ccall "cn_chain_joints" chain p))
    (coerce v 'list)))

(defun chain-limits (chain)
  "Lower and upper joint limits of CHAIN as two DVECs (continuous joints: -pi..pi)."
  (let* ((n (ccall "cn_chain_num_joints" chain)) (lo (make-dvec n)) (hi (make-dvec n)))
    (with-vector-pointers ((pl lo) (ph hi)) (ccall "cn_chain_limits" chain pl ph))
    (values lo hi)))

(defun %q-vec (chain q function what)
  (to-dvec q (ccall "cn_chain_num_joints" chain) function what))

(defun chain-fk (chain q)
  "Pose (DVEC of 7) of CHAIN's tip in its base link frame for joint values Q."
  (let ((qv (%q-vec chain q 'chain-fk "joint values")) (out (make-dvec 7)))
    (with-vector-pointers ((pq qv) (po out)) (ccall "cn_chain_fk" chain pq po))
    out))

(defun chain-may-reach-p (chain position &key (position-tolerance 1d-3))
  "False when no joint values within CHAIN's limits bring its tip within POSITION-TOLERANCE
\(metres) of POSITION (x y z, a sequence of reals in the base link frame): the chain's reach
map, built at its first use, where CHAIN-IK gives such a goal up at once. True otherwise (a
tolerance above 2 mm: always)."
  (let ((p (to-dvec position 3 'chain-may-reach-p "position")))
    (with-vector-pointers ((pp p))
      (= 1 (ccall "cn_chain_may_reach" chain pp
                  (real-arg position-tolerance 'chain-may-reach-p "position tolerance"))))))

(defun chain-ik-memo-size (chain)
  "How many answers of CHAIN-IK the native CHAIN keeps to give again: those its random restarts
play no part in (a goal out of the reach map's reach, a goal solved from the seed), for the same
goal, seed, restart count and tolerances bit for bit. At most 4096: the memo is emptied when
full."
  (ccall "cn_chain_ik_memo_size" chain))

(defconstant +reach-map-params+ 20 "The numbers of a reach map besides its cells (CN_REACH_PARAMS).")

(defun chain-reach-map (chain)
  "CHAIN's reach map as Lisp data, built first when needed: a cons of a DVEC of parameters
\(among them a hash of the chain's joints, limits and tip) and an octet vector of cells. A
chain made again in another process takes it back with SET-CHAIN-REACH-MAP instead of
building it."
  (let ((params (make-dvec +reach-map-params+)))
    (with-vector-pointers ((pp params))
      (let* ((n (ccall "cn_chain_reach_map_get" chain pp (cffi:null-pointer) 0))
             (cells (make-array n :element-type '(unsigned-byte 8))))
        (with-vector-pointers ((cp cells))
          (ccall "cn_chain_reach_map_get" chain pp cp n))
        (cons params cells)))))

(defun set-chain-reach-map (chain map)
  "Give CHAIN the reach map MAP (from CHAIN-REACH-MAP) instead of building it. True when
installed; NIL when MAP is not a map of a chain with CHAIN's joints, limits and tip (then
nothing changes)."
  (destructuring-bind (params . cells) map
    (unless (and (typep params '(simple-array double-float (*)))
                 (= (length params) +reach-map-params+)
                 (typep cells '(simple-array (unsigned-byte 8) (*))))
      (error "SET-CHAIN-REACH-MAP: ~s is not a reach map of CHAIN-REACH-MAP." map))
    (with-vector-pointers ((pp params) (cp cells))
      (= 1 (ccall "cn_chain_reach_map_set" chain pp cp (length cells))))))

(defun chain-ik (chain target-pose &key seed (max-restarts 200) (position-tolerance 1d-3)
                                        (rotation-tolerance 1d-2) (random-seed 1))
  "Joint values (DVEC) placing CHAIN's tip at TARGET-POSE (in the base link frame), within
the joint limits, starting from SEED (default: middle of the limits) and then from random
restarts drawn from RANDOM-SEED.  Returns the joint values, or NIL when no solution within
the tolerances was found; second value: position and rotation error of the best attempt."
  (let* ((n (ccall "cn_chain_num_joints" chain))
         (seed-v (if seed (%q-vec chain seed 'chain-ik "seed")
                     (multiple-value-bind (lo hi) (chain-limits chain)
                       (map 'dvec (lambda (a b) (* 0.5d0 (+ a b))) lo hi))))
         (out (make-dvec n)) (err (make-dvec 2)))
    (unless (typep max-restarts '(integer 0 100000))
      (arg-error 'chain-ik "max-restarts ~s, expected an integer in 0..100000" max-restarts))
    (unless (typep random-seed '(unsigned-byte 32))
      (arg-error 'chain-ik "random-seed ~s, expected a 32-bit unsigned integer" random-seed))
    (let ((status (with-pose-pointer (pt target-pose 'chain-ik)
                    (with-vector-pointers ((ps seed-v) (po out) (pe err))
                      (ccall "cn_chain_ik" chain pt ps max-restarts
                             (real-arg position-tolerance 'chain-ik "position tolerance")
                             (real-arg rotation-tolerance 'chain-ik "rotation tolerance")
                             random-seed po pe)))))
      (values (and (zerop status) out) err))))
