;;;; cram-plans: one system per layer; `cram-plans' loads them all.
;;;; Each layer's files are listed in its own DEFSYSTEM form below.

;; Debian's cxml.asd defines several primary systems in one file: ASDF 3.3 re-reads it, warns
;; and prints closure-common's character checks each time one of them is looked up.  Load cxml
;; once, quietly, and register it and its parts as immutable, so ASDF neither re-reads nor
;; re-plans them (nor recompiles what depends on them).  (The end of this file keeps the load
;; of cxml from counting as a dependency of this file's definitions.)
(unless (asdf:component-loaded-p "cxml")
  (let ((*standard-output* (make-broadcast-stream)))
    (handler-bind ((warning #'muffle-warning))
      (asdf:load-system "cxml")))
  (dolist (name '("cxml" "cxml-xml" "cxml-dom" "cxml-klacks" "closure-common"))
    (when (asdf:find-system name nil)
      (asdf:register-immutable-system name))))

;; Debian's hunchentoot.asd and flexi-streams.asd also define test systems of other names, and
;; ASDF warns each time it reads them (the viewer, part of `cram-plans', loads hunchentoot).
;; Read them once, quietly.
(dolist (name '("flexi-streams" "hunchentoot"))
  (unless (asdf:registered-system name)
    (let ((file (nth-value 2 (asdf:locate-system name))))
      (when file
        (handler-bind ((warning #'muffle-warning))
          (asdf:load-asd file :name name))))))

;; The compiler's optimization notes on this project's files are for its developers, not for a
;; user's first build: every system of this file compiles its files through this function (set
;; at the end of the file; warnings still show).
(defun cram-plans-compile-quietly (thunk)
  "Call THUNK, a compilation, muffling the compiler's optimization notes."
  (handler-bind ((sb-ext:compiler-note #'muffle-warning))
    (funcall thunk)))

;; Debian installs roslisp under /usr/share/roslisp/ and its message systems under
;; /usr/share/common-lisp/ros/, outside ASDF's default registry.  Find systems there as a last
;; resort (after the central registry and the source registry), so that a plain
;; (push ".../cram-plans/" asdf:*central-registry*) loads the ROS integration too; where roslisp
;; is installed, `cram-plans' loads it (feature :CRAM-PLANS-ROSLISP), so the ROSLISP package
;; exists in every cram-plans image.
(defparameter *cram-plans-ros-lisp-trees* '("/usr/share/roslisp/" "/usr/share/common-lisp/ros/")
  "Directory trees searched for Debian's roslisp and ROS message .asd files.")
(defvar *cram-plans-ros-asd-files* nil
  "System name -> .asd file under *CRAM-PLANS-ROS-LISP-TREES*, filled on first use.")
(defun cram-plans-ros-asd-files ()
  (or *cram-plans-ros-asd-files*
      (let ((table (make-hash-table :test 'equal)))
        (dolist (tree *cram-plans-ros-lisp-trees* table)
          (when (uiop:directory-exists-p tree)
            (uiop:collect-sub*directories
             tree t t (lambda (dir)
                        (dolist (file (uiop:directory-files dir "*.asd"))
                          (setf (gethash (pathname-name file) table) file))))))
        (setf *cram-plans-ros-asd-files* table))))
(defun cram-plans-find-ros-system (name)
  "ASDF search function: the .asd file of NAME under Debian's roslisp trees, or NIL."
  (values (gethash (asdf:primary-system-name name) (cram-plans-ros-asd-files))))
(unless (member 'cram-plans-find-ros-system asdf:*system-definition-search-functions*)
  (setf asdf:*system-definition-search-functions*
        (append asdf:*system-definition-search-functions* '(cram-plans-find-ros-system))))
;; (Asked of the search function, not of FIND-SYSTEM: a system looked up while this file loads
;; becomes a dependency of its definitions.)
(when (or (cram-plans-find-ros-system "roslisp") (asdf:registered-system "roslisp"))
  (pushnew :cram-plans-roslisp *features*))

(defsystem "cram-plans/cram-utilities"
  :description "Lazy lists, variable bindings and small utilities (package CUT)."
  :depends-on ("alexandria")
  :pathname "prolog/"
  :serial t
  :components ((:file "utilities-package")
               (:file "lazy")
               (:file "bindings")
               (:file "patmatch")
               (:file "threads")))

(defsystem "cram-plans/cram-prolog"
  :description "The CRAM-dialect Prolog engine, compiled to Lisp closures (package PROLOG)."
  :depends-on ("cram-plans/cram-utilities" "alexandria")
  :pathname "prolog/"
  :serial t
  :components ((:file "prolog-package")
               (:file "terms")
               (:file "predicates")
               (:file "compiler")
               (:file "guards")
               (:file "clauses")
               (:file "control")
               (:file "database")
               (:file "builtins")
               (:file "library")
               (:file "query")
               (:file "rete-memory")
               (:file "rete-alpha")
               (:file "rete-beta")
               (:file "rete")
               (:file "documentation")))

(defsystem "cram-plans/cl-transforms"
  :description "3D vectors, quaternions, poses, transforms, stamped poses, a TF buffer (CL-TRANSFORMS, CL-TRANSFORMS-STAMPED, CL-TF, CRAM-TF)."
  :depends-on ("alexandria" "bordeaux-threads")
  :pathname "src/transforms/"
  :serial t
  :components ((:file "package")
               (:file "checks")
               (:file "vectors")
               (:file "rotations")
               (:file "poses")
               (:file "stamped")
               (:file "transformer")
               (:file "cram-tf")))

(defsystem "cram-plans/cram-math"
  :description "Double-float matrices, sampling from distributions, the multivariate Gaussian,
points in polygons (package CRAM-MATH, CMA)."
  :pathname "src/math/"
  :serial t
  :components ((:file "package")
               (:file "matrix")
               (:file "sampling")))

(defsystem "cram-plans/cram-native"
  :description "CFFI binding of the C shim libcram_native.so (Bullet, urdfdom, assimp, KDL, OSMesa, libpng)."
  :depends-on ("cffi" "alexandria")
  :pathname "projection/"
  :serial t
  :components ((:file "native")
               (:file "native-world")
               (:file "native-robot")
               (:file "native-query")
               (:file "native-sweep")
               (:file "native-render")
               (:file "native-ik")))

(defsystem "cram-plans/cram-walker"
  :description "A code walker that expands plans into plan trees (package CRAM-WALKER, WALKER)."
  :depends-on ("alexandria")
  :pathname "src/walker/"
  :serial t
  :components ((:file "package")
               (:file "walker")))

(defsystem "cram-plans/cram-language"
  :description "The CRAM plan language (CPL): tasks, PAR/PURSUE/TRY-*, failures, fluents, the task tree, logging."
  :depends-on ("alexandria" "bordeaux-threads" "yason" "cram-plans/cram-walker")
  :pathname "src/language/"
  :serial t
  :components ((:file "package")
               (:file "logging")
               (:file "conditions")
               (:file "debugging")
               (:file "implementation-package")
               (:file "task-tree")
               (:file "task-pool")
               (:file "tasks")
               (:file "ordered-start")
               (:file "failures")
               (:file "language")
               (:file "goals")
               (:file "fluents")
               (:file "task-tree-output")
               (:file "task-interface")))

(defsystem "cram-plans/cram-common-failures"
  :description "The failure classes robot plans signal (COMMON-FAIL) and the retry-with-solutions strategies."
  :depends-on ("cram-plans/cram-language" "cram-plans/cram-utilities")
  :pathname "src/language/"
  :serial t
  :components ((:file "common-failures")
               (:file "failure-strategies")))

(defsystem "cram-plans/cram-designators"
  :description "Designators: action, motion, location, object and human descriptions grounded through Prolog (package DESIG)."
  :depends-on ("cram-plans/cram-utilities" "cram-plans/cram-prolog" "cram-plans/cl-transforms")
  :pathname "src/designators/"
  :serial t
  :components ((:file "package")
               (:file "protocol")
               (:file "macros")
               (:file "grounding")
               (:file "location")
               (:file "facts")))

(defsystem "cram-plans/cram-robot-interfaces"
  :description "Interface predicates of robot descriptions and the current robot (package ROB-INT)."
  :depends-on ("cram-plans/cram-prolog" "cram-plans/cram-utilities" "cram-plans/cram-designators")
  :pathname "src/robot-interfaces/"
  :serial t
  :components ((:file "package")
               (:file "interfaces")
               (:file "facts")
               (:file "designators")))

(defsystem "cram-plans/cram-location-costmap"
  :description "Location costmaps and their metadata predicates (package COSTMAP)."
  :depends-on ("cram-plans/cram-prolog" "cram-plans/cram-utilities" "cram-plans/cram-robot-interfaces" "cram-plans/cram-designators"
               "cram-plans/cl-transforms" "cram-plans/cram-native" "cram-plans/cram-bullet-reasoning")
  :pathname "src/location-costmap/"
  :serial t
  :components ((:file "package")
               (:file "metadata")
               (:file "grid")
               (:file "samples")
               (:file "values")
               (:file "functions")
               (:file "belief")
               (:file "sight")
               (:file "targets")
               (:file "designators")
               (:file "household-bodies")
               (:file "household-regions")
               (:file "household-relations")
               (:file "household-robot")
               (:file "heatmap")))

(defsystem "cram-plans/cram-pr2-description"
  :description "The PR2 as robot-description facts keyed by :PR2 (package PR2-DESCR)."
  :depends-on ("cram-plans/cram-prolog" "cram-plans/cram-robot-interfaces" "cram-plans/cram-location-costmap" "cram-plans/cl-transforms")
  :pathname "robots/pr2/"
  :components ((:file "package")
               (:file "general-knowledge" :depends-on ("package"))
               (:file "arms" :depends-on ("package"))
               (:file "neck" :depends-on ("package"))))

(defsystem "cram-plans/cram-pepper-description"
  :description "The Pepper robot as robot-description facts keyed by PEPPER-DESCR:PEPPER."
  :depends-on ("cram-plans/cram-prolog" "cram-plans/cram-robot-interfaces" "cram-plans/cram-location-costmap" "cram-plans/cl-transforms")
  :pathname "robots/pepper/"
  :components ((:file "package")
               (:file "general-knowledge" :depends-on ("package"))
               (:file "arms" :depends-on ("package"))
               (:file "neck" :depends-on ("package"))))

(defsystem "cram-plans/cram-executive"
  :description "PERFORM, process modules, events and occasions, projection environments (EXE, CPM, COE, CPOE, PROJ)."
  :depends-on ("cram-plans/cram-utilities" "cram-plans/cram-prolog" "cram-plans/cram-designators" "cram-plans/cram-language"
               "cram-plans/cram-common-failures")
  :pathname "src/executive/"
  :serial t
  :components ((:file "executive-package")
               (:file "occasions-events")
               (:file "plan-events")
               (:file "process-modules")
               (:file "asynchronous-process-modules")
               (:file "projection")
               (:file "projection-clocks")
               (:file "perform")))

(defsystem "cram-plans/cram-bullet-reasoning"
  :description "The Bullet belief state: URDF models (CL-URDF), worlds and objects, Prolog
predicates, headless pictures and visibility (BTR), tutorial helpers (BTR-UTILS)."
  :depends-on ("cram-plans/cram-utilities" "cram-plans/cram-prolog" "cram-plans/cl-transforms" "cram-plans/cram-native"
               "cram-plans/cram-robot-interfaces" "cxml" "trivial-garbage" "bordeaux-threads")
  :pathname "projection/btr/"
  :serial t
  :components ((:file "package")
               (:file "urdf")
               (:file "urdf-tree")
               (:file "urdf-writer")
               (:file "world")
               (:file "objects")
               (:file "meshes")
               (:file "robot")
               (:file "queries")
               (:file "pictures")
               (:file "facts")
               (:file "utils")
               (:file "costmap-vis")
               (:file "world-api")
               (:file "bounding-boxes")
               (:file "timeline")))

(defsystem "cram-plans/cram-common-designators"
  :description "MOTION-GROUNDING rules of the robot-independent motions and WAIT-PM (COMMON-DESIG)."
  :depends-on ("cram-plans/cram-prolog" "cram-plans/cram-utilities" "cram-plans/cram-designators" "cram-plans/cram-executive"
               "cram-plans/cram-language" "cram-plans/cl-transforms")
  :pathname "projection/urdf-proj/"
  :serial t
  :components ((:file "motions-package")
               (:file "motions")))

(defsystem "cram-plans/cram-urdf-projection"
  :description "The simulated robot: motions teleport the robot of the Bullet belief state, with
IK, collision checks, TF and process modules (URDF-PROJ, alias PR2-PROJ)."
  :depends-on ("cram-plans/cram-bullet-reasoning" "cram-plans/cram-native" "cram-plans/cram-common-designators" "cram-plans/cram-executive"
               "cram-plans/cram-language" "cram-plans/cram-common-failures" "cram-plans/cram-robot-interfaces" "cram-plans/cram-designators"
               "cram-plans/cl-transforms" "cram-plans/cram-prolog" "cram-plans/cram-utilities")
  :pathname "projection/urdf-proj/"
  :serial t
  :components ((:file "package")
               (:file "robot")
               (:file "tf")
               (:file "contacts")
               (:file "sweep")
               (:file "low-level-base")
               (:file "ik")
               (:file "ik-solver")
               (:file "low-level-arms")
               (:file "reach-memory")
               (:file "low-level-tcp")
               (:file "process-modules")
               (:file "projection-environment")))

(defsystem "cram-plans"
  :description "CRAM plans with a Bullet belief state for projection: all layers."
  :version "0.1.0"
  :depends-on ("cram-plans/cram-utilities" "cram-plans/cram-prolog" "cram-plans/cl-transforms" "cram-plans/cram-native"
               "cram-plans/cram-language" "cram-plans/cram-common-failures" "cram-plans/cram-math"
               "cram-plans/cram-robot-interfaces" "cram-plans/cram-location-costmap"
               "cram-plans/cram-pr2-description" "cram-plans/cram-pepper-description"
               "cram-plans/cram-designators" "cram-plans/cram-executive" "cram-plans/cram-bullet-reasoning"
               "cram-plans/cram-common-designators" "cram-plans/cram-urdf-projection"
               "cram-plans/cram-object-knowledge" "cram-plans/cram-household-knowledge"
               "cram-plans/cram-mobile-pick-place-plans"
               "cram-plans/cram-urdf-environment-manipulation"
               "cram-plans/cram-fetch-deliver-plans" "cram-plans/cram-projection-demos"
               "cram-plans/ros-load" "cram-plans/roslisp-utilities" "cram-plans/cram-bullet-world-tutorial" "cram-plans/cram-pepper-demo"
               "cram-plans/compat" "cram-plans/replay" "cram-plans/viewer" "cram-plans/cram-ros-pms/package"
               (:feature :cram-plans-roslisp "cram-plans/roslisp-utilities/ros")
               (:feature :cram-plans-roslisp "cram-plans/cram-urdf-environment-manipulation/ros")))

(defsystem "cram-plans/cram-ros-pms/package"
  :description "The light part of the robot process modules: package CRAM-ROS-PMS (PR2-PMS),
ROBOT-CONNECTION-ERROR and WITH-REAL-ROBOT, which loads cram-plans/cram-ros-pms on first use."
  :pathname "src/robot-ros/"
  :components ((:file "package")))

(defsystem "cram-plans/cram-ros-pms"
  :description "Plans on a robot over ROS 1 (docs/robot-over-ros.md): process modules for
move_base, joint trajectory controllers and perception/objects, an actionlib client, and the
belief state following /joint_states and TF."
  :depends-on ("cram-plans/cram-ros-pms/package" "cram-plans/roslisp-utilities/ros"
               "cram-plans/cram-urdf-projection" "cram-plans/cram-pr2-description"
               "cram-plans/cram-common-designators" "cram-plans/cram-executive"
               "roslisp" "sensor_msgs-msg" "trajectory_msgs-msg" "move_base_msgs-msg"
               "actionlib_msgs-msg" "visualization_msgs-msg" "tf2_msgs-msg" "geometry_msgs-msg"
               "std_msgs-msg" "sb-posix" "sb-bsd-sockets")
  :pathname "src/robot-ros/"
  :serial t
  :components ((:file "connection")
               (:file "actionlib")
               (:file "actionlib-api")
               (:file "actionlib-simple-client")
               (:file "robot")
               (:file "motions")
               (:file "process-modules")
               (:file "sim-robot")))

(defsystem "cram-plans/replay"
  :description "Recording of projection runs for the browser viewer (CRAM-VIEWER): states after
each motion, replays written to disk, and BTR:VIEWER / BTR:DEBUG-WINDOW, which load the server
(cram-plans/viewer) on first use."
  :depends-on ("cram-plans/cram-bullet-reasoning" "cram-plans/cram-urdf-projection"
               "cram-plans/cram-location-costmap" "cram-plans/cram-language" "cl-base64" "cl-ppcre")
  :pathname "projection/viewer/"
  :serial t
  :components ((:file "package")
               (:file "scene")
               (:file "recorder")
               (:file "sweeps")
               (:file "export")
               (:file "entry")
               (:static-file "viewer.js")
               (:static-file "viewer.css")))

(defsystem "cram-plans/viewer"
  :description "The browser viewer of the belief state: hunchentoot serves a three.js page (from
Debian's libjs-three) that follows the world live (server-sent events) and replays runs."
  :depends-on ("cram-plans/replay" "hunchentoot")
  :pathname "projection/viewer/"
  :components ((:file "server")))

(defsystem "cram-plans/compat"
  :description "CRAM compatibility for the seed-era (2017) API: PR2-PP-PLANS, the init functions
called by hand, CRAM-PR2-DESCRIPTION:PR2, ROBOT-ARMS-PARKING-JOINT-STATES, the old location
vocabulary ((:to :see) (:on \"CounterTop\") ...), MOVING-JOINTS and LOOKING-AT, as aliases."
  :depends-on ("cram-plans/cram-bullet-world-tutorial")
  :pathname "src/compat/"
  :serial t
  :components ((:file "compat-package")
               (:file "compat-occupancy")
               (:file "compat-world")
               (:file "compat-designators")
               (:file "compat-pp-plans")))

(defsystem "cram-plans/tests/compat"
  :depends-on ("cram-plans/tests/base" "cram-plans/compat")
  :pathname "tests/"
  :components ((:file "compat-tests")))

(defsystem "cram-plans/roslisp-utilities"
  :description "ROS integration without roslisp: init and cleanup functions, URDFs from the
parameter server with the embedded files as fallback, the master probe, the belief state as TF
edges and markers. STARTUP-ROS loads roslisp-utilities/ros (roslisp) when it is first called."
  :depends-on ("cram-plans/cram-bullet-reasoning" "cram-plans/cl-transforms" "cram-plans/cram-robot-interfaces"
               "bordeaux-threads" "sb-bsd-sockets")
  :pathname "src/ros/"
  :serial t
  :components ((:file "package")
               (:file "ros-home")
               (:file "master")
               (:file "names")
               (:file "registry")
               (:file "description")
               (:file "worlds")
               (:file "belief-tf")
               (:file "belief-markers")))

(defsystem "cram-plans/roslisp-utilities/ros-home"
  :description "Makes the ROS home directory before roslisp loads (roslisp hangs without it)."
  :depends-on ("cram-plans/roslisp-utilities")
  :pathname "src/ros/"
  :components ((:file "ros-home-now")))

(defsystem "cram-plans/roslisp-utilities/ros"
  :description "The roslisp part of roslisp-utilities (Debian's roslisp and message systems):
the node, parameters, publishing the belief state on /tf and /visualization_marker_array."
  :depends-on ("cram-plans/roslisp-utilities" "cram-plans/roslisp-utilities/ros-home" "sb-posix"
               "cram-plans/ros-load"
               "roslisp" "std_msgs-msg" "geometry_msgs-msg" "tf2_msgs-msg" "visualization_msgs-msg")
  :pathname "src/ros/"
  :serial t
  :components ((:file "node")
               (:file "publisher")))

;;; Tests: one system per layer, all run by cram-plans-tests.

(defsystem "cram-plans/tests/base"
  :depends-on ("fiveam")
  :pathname "tests/"
  :components ((:file "suite")))

(defsystem "cram-plans/tests/utilities"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-utilities")
  :pathname "tests/"
  :serial t
  :components ((:file "utilities-tests")
               (:file "cut-pattern-tests")))

(defsystem "cram-plans/tests/cram-math"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-math")
  :pathname "tests/"
  :components ((:file "cram-math-tests")))

(defsystem "cram-plans/tests/prolog"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-prolog")
  :pathname "tests/"
  :serial t
  :components ((:file "prolog-tests")
               (:file "prolog-builtin-tests")
               (:file "prolog-engine-tests")
               (:file "prolog-api-tests")
               (:file "prolog-rete-tests")
               (:file "prolog-rete-network-tests")))

(defsystem "cram-plans/tests/transforms"
  :depends-on ("cram-plans/tests/base" "cram-plans/cl-transforms")
  :pathname "tests/"
  :serial t
  :components ((:file "transforms-tests")
               (:file "transforms-tf-tests")
               (:file "transforms-quaternion-tests")))

(defsystem "cram-plans/tests/native"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-native" "sb-posix")
  :pathname "tests/"
  :serial t
  :components ((:file "native-tests")
               (:file "native-queries-tests")
               (:file "native-float-modes-tests")
               (:file "native-fuzz-tests")
               (:file "native-ik-tests")
               (:file "native-reach-map-tests")))

(defsystem "cram-plans/tests/language"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-language" "cram-plans/cram-common-failures")
  :pathname "tests/"
  :serial t
  :components ((:file "language-tests")
               (:file "language-tree-tests")
               (:file "cpl-api-tests")
               (:file "cpl-tasks-tests")
               (:file "cpl-task-threads-tests")
               (:file "cpl-ordered-start-tests")
               (:file "cram-walker-tests")
               (:file "language-quiet-log-tests")))

(defsystem "cram-plans/tests/robots"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-robot-interfaces" "cram-plans/cram-location-costmap"
               "cram-plans/cram-pr2-description" "cram-plans/cram-pepper-description" "cxml")
  :pathname "tests/"
  :serial t
  :components ((:file "robots-tests")
               (:file "robots-pepper-tests")
               (:file "robots-urdf-tests")
               (:file "robot-interfaces-api-tests")))

(defsystem "cram-plans/tests/designators"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-designators")
  :pathname "tests/"
  :serial t
  :components ((:file "designators-tests")
               (:file "designators-grounding-tests")
               (:file "designator-type-index-tests")
               (:file "designator-classes-tests")))

(defsystem "cram-plans/tests/executive"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-executive")
  :pathname "tests/"
  :serial t
  :components ((:file "executive-tests")
               (:file "location-solution-tests")
               (:file "process-module-tests")
               (:file "projection-clock-tests")))

(defsystem "cram-plans/tests/btr"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-bullet-reasoning" "cram-plans/cram-pr2-description"
               "sb-posix")
  :pathname "tests/"
  :serial t
  :components ((:file "btr-tests")
               (:file "btr-api-tests")
               (:file "btr-compound-tests")
               (:file "btr-errors-tests")))

(defsystem "cram-plans/tests/scripts"
  :depends-on ("cram-plans/tests/base")
  :pathname "tests/"
  :components ((:file "scripts-tests")))

(defsystem "cram-plans/tests/ros"
  :depends-on ("cram-plans/tests/base" "cram-plans/roslisp-utilities" "cram-plans/roslisp-utilities/ros"
               "cram-plans/ros-load" "sb-posix")
  :pathname "tests/"
  :serial t
  :components ((:file "ros-tests")
               (:file "ros-live-tests")
               (:file "ros-world-tests")))

(defsystem "cram-plans/tests/urdf-proj"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-urdf-projection" "cram-plans/cram-pr2-description"
               "cram-plans/cram-pepper-description")
  :pathname "tests/"
  :serial t
  :components ((:file "urdf-proj-tests")
               (:file "urdf-proj-ik-fallback-tests")
               (:file "urdf-proj-arm-ik-tests")
               (:file "urdf-proj-collision-check-tests")
               (:file "urdf-proj-reach-memory-tests")))

(defsystem "cram-plans/tests/costmap"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-location-costmap" "cram-plans/cram-pr2-description")
  :pathname "tests/"
  :serial t
  :components ((:file "costmap-tests")
               (:file "costmap-kitchen-tests")
               (:file "costmap-api-tests")
               (:file "costmap-fast-paths-tests")
               (:file "costmap-sampling-tests")))

(defsystem "cram-plans/tests/bad-input"
  :description "The table-driven bad-input suite of every layer a user touches."
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-prolog" "cram-plans/cram-language"
               "cram-plans/cram-common-failures" "cram-plans/cl-transforms" "cram-plans/cram-designators"
               "cram-plans/cram-executive" "cram-plans/cram-bullet-reasoning"
               "cram-plans/cram-location-costmap" "cram-plans/cram-urdf-projection"
               "cram-plans/cram-pr2-description")
  :pathname "tests/"
  :serial t
  :components ((:file "bad-input-tests")
               (:file "bad-input-projection-tests")))

(defsystem "cram-plans/tests/runner"
  :depends-on ("cram-plans/tests/base" "yason" "sb-posix")
  :pathname "tests/"
  :components ((:file "runner-tests")))

(defsystem "cram-plans/tests"
  :description "Every FiveAM suite of cram-plans, under the suite CRAM-PLANS-TESTS:ALL."
  :depends-on ("cram-plans/tests/utilities" "cram-plans/tests/prolog"
               "cram-plans/tests/transforms" "cram-plans/tests/native"
               "cram-plans/tests/language"
               "cram-plans/tests/robots"
               "cram-plans/tests/designators" "cram-plans/tests/executive"
               "cram-plans/tests/costmap"
               "cram-plans/tests/btr" "cram-plans/tests/scripts"
               "cram-plans/tests/ros" "cram-plans/tests/urdf-proj"
               "cram-plans/tests/plans" "cram-plans/tests/runner" "cram-plans/tests/compat" "cram-plans/tests/seeds"
               "cram-plans/tests/bad-input" "cram-plans/tests/readme" "cram-plans/tests/robot-ros"
               "cram-plans/tests/environment-manipulation" "cram-plans/tests/environment-manipulation-ros"
               "cram-plans/tests/household" "cram-plans/tests/fetch-deliver" "cram-plans/tests/household-demo"
               "cram-plans/tests/viewer-report" "cram-plans/tests/cram-math"
               "cram-plans/tests/repl" "cram-plans/tests/actionlib" "cram-plans/tests/sweep"))

(defsystem "cram-plans/tests/sweep"
  :description "Sweep checks between key poses: the shim's call and the motions' *SWEEP-CHECK*."
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-urdf-projection" "cram-plans/cram-pr2-description"
               "cram-plans/cram-bullet-world-tutorial" "cram-plans/replay")
  :pathname "tests/"
  :components ((:file "sweep-tests") (:file "contact-prefilter-tests")))

(defsystem "cram-plans/tests/robot-ros"
  :description "Plans over ROS against the simulated robot node (tools/ros/sim_robot.py)."
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-ros-pms" "cram-plans/cram-bullet-world-tutorial"
               "sb-posix")
  :pathname "tests/"
  :components ((:file "robot-ros-tests")))

(defsystem "cram-plans/tests/repl"
  :description "A user's day at the REPL: a swank server and a client speaking SLIME's protocol,
reloads, the debugger inside plans, logging."
  :depends-on ("cram-plans/tests/base" "cram-plans" "sb-posix" "sb-bsd-sockets")
  :pathname "tests/"
  :serial t
  :components ((:file "swank-client")
               (:file "repl-tests")
               (:file "repl-debugger-tests")))

(defsystem "cram-plans/tests/actionlib"
  :description "CRAM's actionlib client and the example gripper process module against a rospy
action server on a private ROS master."
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-ros-pms" "actionlib-msg")
  :pathname "tests/"
  :components ((:file "actionlib-tests")))

(defsystem "cram-plans/tests/readme"
  :description "The README's lisp and sh blocks, verbatim, in fresh SBCLs and bash."
  :depends-on ("cram-plans/tests/ros")
  :pathname "tests/"
  :components ((:file "readme-tests")))

(defsystem "cram-plans/tests/viewer"
  :description "The browser viewer: its scene and replay data, and the page in headless Chromium."
  :depends-on ("cram-plans/tests/base" "cram-plans/viewer" "cram-plans/cram-bullet-world-tutorial"
               "yason" "sb-posix")
  :pathname "tests/"
  :components ((:file "viewer-tests")))

(defsystem "cram-plans/tests/viewer-report"
  :description "The viewer's /report endpoint, without a browser."
  :depends-on ("cram-plans/tests/base" "cram-plans/viewer" "sb-bsd-sockets")
  :pathname "tests/"
  :components ((:file "viewer-report-tests")))

(defsystem "cram-plans/tests/seeds"
  :description "Seed replays: tests/seeds/seed-NNN.lisp, each in a fresh SBCL."
  :depends-on ("cram-plans/tests/base")
  :pathname "tests/"
  :components ((:file "seeds-tests")))

;;; Plans, object knowledge, tutorials and demos.

(defsystem "cram-plans/cram-object-knowledge"
  :description "Manipulation interfaces (MAN-INT) and household object knowledge (OBJECTS):
grasps, gripper openings and efforts, pick and place trajectories."
  :depends-on ("cram-plans/cl-transforms")
  :pathname "src/plans/"
  :serial t
  :components ((:file "manipulation-interfaces")
               (:file "object-knowledge")))

(defsystem "cram-plans/cram-household-knowledge"
  :description "Household object knowledge (OBJECTS, MAN-INT): the kitchen's object types,
their grasps with pregrasp and lift per location type, carry configurations, and where objects
are likely to be and where they go per context (GET-OBJECT-LIKELY-LOCATION,
GET-OBJECT-DESTINATION)."
  :depends-on ("cram-plans/cram-object-knowledge" "cram-plans/cram-designators" "cram-plans/cl-transforms")
  :pathname "src/object-knowledge/"
  :serial t
  :components ((:file "household-types")
               (:file "household-grasps")
               (:file "knowledge-dispatch")
               (:file "household-locations")))

(defsystem "cram-plans/cram-mobile-pick-place-plans"
  :description "Action groundings and plans of mobile pick and place (PP-PLANS)."
  :depends-on ("cram-plans/cram-prolog" "cram-plans/cram-utilities" "cram-plans/cl-transforms" "cram-plans/cram-designators"
               "cram-plans/cram-language" "cram-plans/cram-common-failures" "cram-plans/cram-executive"
               "cram-plans/cram-robot-interfaces" "cram-plans/cram-bullet-reasoning" "cram-plans/cram-object-knowledge"
               "cram-plans/cram-household-knowledge" "cram-plans/cram-urdf-projection")
  :pathname "src/plans/"
  :serial t
  :components ((:file "pp-package")
               (:file "atomic-actions")
               (:file "pick-place")))

(defsystem "cram-plans/ros-load"
  :description "ROS-LOAD:LOAD-SYSTEM, mapping ROS package names to this project's systems."
  :pathname "src/tutorials/"
  :components ((:file "ros-load")))

(defsystem "cram-plans/cram-bullet-world-tutorial"
  :description "The Bullet world tutorials (BTW-TUT): init-projection, move-bottle, switching two
bottles."
  :depends-on ("cram-plans/cram-prolog" "cram-plans/cram-utilities" "cram-plans/cl-transforms" "cram-plans/cram-designators"
               "cram-plans/cram-language" "cram-plans/cram-common-failures" "cram-plans/cram-executive"
               "cram-plans/cram-robot-interfaces" "cram-plans/cram-bullet-reasoning" "cram-plans/cram-pr2-description"
               "cram-plans/cram-location-costmap" "cram-plans/cram-common-designators" "cram-plans/cram-urdf-projection"
               "cram-plans/cram-object-knowledge" "cram-plans/cram-mobile-pick-place-plans" "cram-plans/ros-load"
               "cram-plans/roslisp-utilities")
  :pathname "src/tutorials/"
  :serial t
  :components ((:file "btw-tut-setup")
               (:file "btw-tut-move-bottle")
               (:file "btw-tut-switch-bottles")))

(defsystem "cram-plans/cram-pepper-demo"
  :description "Pepper as a shopping assistant (DEMO): the shop, the menus, the product search."
  :depends-on ("cram-plans/cram-bullet-world-tutorial" "cram-plans/cram-pepper-description")
  :pathname "src/tutorials/"
  :serial t
  :components ((:file "pepper-setup")
               (:file "pepper-shelf-prolog")
               (:file "pepper-plans")
               (:file "pepper-search")))

(defsystem "cram-plans/cram-fetch-deliver-plans"
  :description "The household action layer (FD-PLANS): navigating, turning towards, searching,
fetching, delivering and transporting, with CRAM's retries and projection pre-checks."
  :depends-on ("cram-plans/cram-mobile-pick-place-plans" "cram-plans/cram-location-costmap"
               "cram-plans/cram-urdf-projection" "cram-plans/cram-household-knowledge"
               "cram-plans/cram-urdf-environment-manipulation")
  :pathname "src/fetch-deliver/"
  :serial t
  :components ((:file "fd-package")
               (:file "fd-occasions")
               (:file "fd-placing-memory")
               (:file "fd-fill-order")
               (:file "fd-prechecks")
               (:file "fd-navigation")
               (:file "fd-search")
               (:file "fd-fetch")
               (:file "fd-deliver")
               (:file "fd-transport")
               (:file "fd-groundings")))

(defsystem "cram-plans/cram-projection-demos"
  :description "CRAM's household demo in projection (DEMOS): set a breakfast table from closed
containers, then clean it up."
  :depends-on ("cram-plans/cram-fetch-deliver-plans" "cram-plans/cram-bullet-world-tutorial")
  :pathname "src/demos/"
  :serial t
  :components ((:file "demos-package")
               (:file "varied-kitchen")
               (:file "household-demo")))

(defsystem "cram-plans/tests/fetch-deliver"
  :description "Searching, fetching, delivering and transporting (FD-PLANS)."
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-fetch-deliver-plans"
               "cram-plans/cram-bullet-world-tutorial")
  :pathname "tests/"
  :components ((:file "fetch-deliver-tests")))

(defsystem "cram-plans/tests/household-demo"
  :description "CRAM's household demo in projection (DEMOS)."
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-projection-demos")
  :pathname "tests/"
  :components ((:file "household-demo-tests")))

(defsystem "cram-plans/tests/household"
  :description "Household object knowledge and location designators in the kitchen."
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-bullet-world-tutorial")
  :pathname "tests/"
  :serial t
  :components ((:file "household-knowledge-tests")
               (:file "household-locations-tests")))

(defsystem "cram-plans/tests/plans"
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-bullet-world-tutorial" "cram-plans/cram-pepper-demo")
  :pathname "tests/"
  :components ((:file "plans-tests") (:file "plans-placing-tests") (:file "scene-layout-tests")))

;;; Environment manipulation: drawers, doors and what is inside them.

(defsystem "cram-plans/cram-urdf-environment-manipulation"
  :description "Opening, closing, accessing and sealing the drawers and doors of an articulated
environment, container events and attachments in the belief state, the container occasions
(ENV-MAN)."
  :depends-on ("cram-plans/cram-prolog" "cram-plans/cram-utilities" "cram-plans/cl-transforms"
               "cram-plans/cram-designators" "cram-plans/cram-language" "cram-plans/cram-common-failures"
               "cram-plans/cram-executive" "cram-plans/cram-robot-interfaces"
               "cram-plans/cram-bullet-reasoning" "cram-plans/cram-native" "cram-plans/cram-urdf-projection"
               "cram-plans/cram-object-knowledge" "cram-plans/cram-mobile-pick-place-plans")
  :pathname "src/environment-manipulation/"
  :serial t
  :components ((:file "package")
               (:file "container-types")
               (:file "containers")
               (:file "trajectories")
               (:file "base-poses")
               (:file "belief")
               (:file "occasions")
               (:file "plans")
               (:file "access-seal")
               (:file "groundings")))

(defsystem "cram-plans/cram-urdf-environment-manipulation/ros"
  :description "The environment's joint states on kitchen/cram_joint_states after container
events, while a ROS node runs."
  :depends-on ("cram-plans/cram-urdf-environment-manipulation" "cram-plans/roslisp-utilities/ros"
               "roslisp" "sensor_msgs-msg" "std_msgs-msg")
  :pathname "src/environment-manipulation/"
  :components ((:file "ros-joint-states")))

(defsystem "cram-plans/tests/environment-manipulation"
  :description "Drawers and doors: grounding, distances, trajectories, the belief state, goals,
attachments and the plans of opening, closing, accessing and sealing."
  :depends-on ("cram-plans/tests/base" "cram-plans/cram-bullet-world-tutorial"
               "cram-plans/cram-urdf-environment-manipulation" "cram-plans/replay")
  :pathname "tests/"
  :components ((:file "environment-manipulation-tests")))

(defsystem "cram-plans/tests/environment-manipulation-ros"
  :description "Environment manipulation with a ROS node: the kitchen's joint states on ROS."
  :depends-on ("cram-plans/tests/environment-manipulation" "cram-plans/tests/ros"
               "cram-plans/cram-urdf-environment-manipulation/ros")
  :pathname "tests/"
  :components ((:file "environment-manipulation-ros-tests")))

;;; Every system of this file compiles through CRAM-PLANS-COMPILE-QUIETLY.
(dolist (name (asdf:registered-systems))
  (when (or (string= name "cram-plans") (uiop:string-prefix-p "cram-plans/" name))
    (reinitialize-instance (asdf:registered-system name)
                           :around-compile 'cram-plans-compile-quietly)))

;;; Loading cxml and reading hunchentoot.asd at the top of this file made ASDF record them as
;;; dependencies of this file's definitions; outside a LOAD-SYSTEM an immutable system counts as
;;; not done, so the next FIND-SYSTEM (e.g. SYSTEM-RELATIVE-PATHNAME) would read this file again
;;; and redefine, and so reload, every system in it.  Nothing in this file depends on them.
(let ((system (asdf:registered-system "cram-plans")))
  (when system
    (setf (asdf/system:definition-dependency-list system) '())
    (let ((set (asdf/system:definition-dependency-set system)))
      (when (hash-table-p set) (clrhash set)))))
