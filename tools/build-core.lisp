;;;; The saved SBCL core of tools/cram-plans-run: cram-plans and the tool (tools/demo.lisp,
;;;; tools/runner.lisp) loaded, so that the tool and its campaign workers start in a fraction of
;;;; a second instead of loading the systems. tools/cram-plans-core decides when a core is stale
;;;; (a hash of its inputs names it) and runs, in a child SBCL that has loaded tools/demo.lisp:
;;;;   (load "tools/build-core.lisp") (cram-plans-demo::save-core "/path/KEY.core")
;;;; Nothing native survives in a saved core (the shared object is reopened, its heap is new),
;;;; so SAVE-CORE releases the load-time belief state and RESTORE-CORE, an SB-EXT:*INIT-HOOKS*
;;;; function, rebuilds the native and environment-derived state when the core starts.

(in-package :cram-plans-demo)

(defun environment-viewer-p ()
  "The value CRAM-VIEWER::*START-VIEWER-FROM-DEBUG-WINDOW* gets when projection/viewer/entry.lisp
loads: true unless CRAM_PLANS_VIEWER is 0, no, off or false."
  (not (member (uiop:getenv "CRAM_PLANS_VIEWER") '("0" "no" "off" "false") :test #'equalp)))

(defun restore-core ()
  "Run when the saved core starts (SB-EXT:*INIT-HOOKS*, after SBCL reopened libcram_native.so):
UIOP's restore hooks (temporary directory, standard streams, command line, cache directory from
this process's environment), the package paths of the native library's resolver, a new empty belief
state, and the variables that loading computed from the environment."
  (uiop:call-image-restore-hook)
  (loop for (name . directory) in (reverse btr::*ros-package-directories*)
        do (cram-native:add-package-path name (namestring directory)))
  (setf btr:*current-bullet-world* (make-instance 'btr:bt-reasoning-world))
  (let ((viewer (find-symbol "*START-VIEWER-FROM-DEBUG-WINDOW*" :cram-viewer)))
    (when (and viewer (boundp viewer))
      (setf (symbol-value viewer) (environment-viewer-p)))))

(defparameter *warm-up-specials*
  '(btw-tut::*robot-urdf* btw-tut::*kitchen-urdf* rob-int:*robot-name* rob-int:*robot-urdf*
    btr:*environment-name* btr:*mesh-files* cram-tf:*robot-base-frame* cram-tf:*tf-default-timeout*
    prolog:*break-on-lisp-errors*)
  "The variables BTW-TUT:INIT-PROJECTION sets: WARM-UP puts their values back. (BTW-TUT's
read-once URDFs must come from the ROS parameters when a node runs in the new process.)")

(defparameter *warm-up-runs* 1
  "How many move-bottle campaign runs WARM-UP makes after the belief state. A plan's first run
in a process compiles what PCL makes on first use (the optimized constructors of MAKE-INSTANCE,
the dispatch functions of the generic functions on its way: some 0.1 s); made before the core
is saved, a campaign worker starts with them.")

(defun warm-up ()
  "Make one belief state the way campaign runs do, so that the saved core holds what this costs
a new process the first time in Lisp: the compiled dispatch functions and constructors of the
generic functions on the way, and (*PREPARSED-URDFS*) the parsed URDFs of the model files;
then *WARM-UP-RUNS* move-bottle campaign runs, for what a plan compiles on first use. The
variables INIT-PROJECTION sets and the random states are put back; SAVE-CORE destroys the
worlds. (A campaign run does not depend on the runs its process made before it: see
RESET-PROJECTION.)"
  (let ((saved (mapcar (lambda (s) (if (boundp s) (list (symbol-value s)) '())) *warm-up-specials*))
        (random-states (list (make-random-state *random-state*)
                             (make-random-state urdf-proj:*ik-random-state*)
                             (make-random-state costmap:*costmap-random-state*)))
        (parsed '()))
    (sb-int:encapsulate 'cl-urdf:parse-urdf 'record
                        (lambda (parse &rest args)
                          (let ((robot (apply parse args)))
                            (when (and (= 1 (length args)) (stringp (first args)))
                              (push (cons (copy-seq (first args)) robot) parsed))
                            robot)))
    (unwind-protect
         (progn
           (dolist (s '(btw-tut::*robot-urdf* btw-tut::*kitchen-urdf*)) (setf (symbol-value s) nil))
           (btw-tut:init-projection)
           (sb-int:unencapsulate 'cl-urdf:parse-urdf 'record)
           (setf *preparsed-urdfs* (reverse parsed))
           ;; not a run anyone replays: the recorder (whose setting the plan's threads read
           ;; globally) is off, so it records no run and the new process numbers its runs from 1
           (let ((record cram-viewer:*record-runs*))
             (setf cram-viewer:*record-runs* nil)
             (unwind-protect
                  (progn
                    (dotimes (i *warm-up-runs*)
                      (move-bottle-run-record 1 i))
                    ;; every arm's IK chain, for its reach map (SAVE-CORE keeps them)
                    (dolist (arm (urdf-proj::robot-arms))
                      (urdf-proj:arm-ik-chain arm (btr:get-robot-object))))
               (setf cram-viewer:*record-runs* record))))
      (sb-int:unencapsulate 'cl-urdf:parse-urdf 'record)
      (loop for s in *warm-up-specials* for v in saved
            do (if v (setf (symbol-value s) (first v)) (makunbound s)))
      (setf *random-state* (first random-states)
            urdf-proj:*ik-random-state* (second random-states)
            costmap:*costmap-random-state* (third random-states)))))

(defun neutralize-worlds ()
  "Destroy every Lisp world object's native world and give it the handle -1: a new process
numbers its worlds from the start again, so an old object must never name a new world."
  (let ((worlds '()))
    (sb-sys:without-gcing
      (sb-vm:map-allocated-objects
       (lambda (object type size)
         (declare (ignore type size))
         (when (typep object 'btr:bt-world) (push object worlds)))
       :dynamic))
    (dolist (world worlds (length worlds))
      (let ((handle (and (slot-boundp world 'btr::handle) (btr:world-handle world)))) ; (not so in the class prototype)
        (when (and (integerp handle) (cram-native:world-alive-p handle))
          (btr:destroy-world world))
        (tg:cancel-finalization world)
        (when handle (setf (slot-value world 'btr::handle) -1))))))

(defun save-core (path)
  "Save this image, with RESTORE-CORE as an init hook, as the SBCL core PATH and exit. Signals
an error instead when the image holds something a core cannot keep (other threads, native
worlds besides the load-time belief state)."
  (let ((others (remove sb-thread:*current-thread* (sb-thread:list-all-threads))))
    (when others
      (error "SAVE-CORE: other threads run: ~s" others)))
  ;; The first ASDF lookup of a process that loaded cram-plans.asd with ASDF:LOAD-ASD loads the
  ;; .asd again (~0.1 s; ASDF:SYSTEM-RELATIVE-PATHNAME in the first run does one): do it here.
  (asdf:find-system "cram-plans")
  (warm-up)
  ;; the plan threads WARM-UP's runs left waiting for tasks
  (cpl:stop-idle-task-threads)
  ;; The belief states made at load time and by WARM-UP: their native worlds will not exist in
  ;; the new process, and a finalizer would destroy whichever new world gets the same handle.
  (setf btr:*current-bullet-world* nil)
  ;; foreign copies of URDF texts (the preparsed ones' among them) live in this process's heap
  (clrhash cram-native::*urdf-foreign-strings*)
  ;; native IK chains, cached by URDF model (a preparsed model would find a stale one);
  ;; their reach maps, built at the first IK call of WARM-UP's run, are kept for the chains of
  ;; the new process
  (urdf-proj::keep-reach-maps)
  (urdf-proj::clear-ik-chain-cache)
  (sb-ext:gc :full t)
  (neutralize-worlds)
  (let ((live (cram-native:world-count)))
    (unless (zerop live)
      (error "SAVE-CORE: ~d native world~:p still alive: a core cannot keep them" live)))
  ;; a new process starts with SBCL's initial random state, as one that loads the systems does
  ;; (tools/cram-plans-core keeps it before loading: compiling a file draws temporary names)
  (let ((initial (find-symbol "*INITIAL-RANDOM-STATE*" :cl-user)))
    (when (and initial (boundp initial))
      (setf *random-state* (make-random-state (symbol-value initial)))))
  (setf *saved-core-p* t)
  (setf sb-ext:*init-hooks* (append (remove 'restore-core sb-ext:*init-hooks*) '(restore-core)))
  ;; not UIOP:CALL-IMAGE-DUMP-HOOK: it clears ASDF's configuration, and the first ASDF lookup of
  ;; the new process (ASDF:SYSTEM-RELATIVE-PATHNAME in the first run) would scan the source
  ;; registry's trees again. The core's key covers that configuration (CL_SOURCE_REGISTRY).
  (sb-ext:gc :full t)
  (sb-ext:save-lisp-and-die path :executable nil))
