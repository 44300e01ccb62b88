;;;; Mesh objects and the mesh keyword list; ROS package directories for package:// URIs.

(in-package :cram-bullet-reasoning)

(defvar *ros-package-directories* '()
  "Alist: ROS package name → directory, consulted before ROS_PACKAGE_PATH.")

(defun register-ros-package (name directory)
  "Make package://NAME/... resolve to files under DIRECTORY (for meshes and URDFs)."
  (let ((dir (uiop:ensure-directory-pathname directory)))
    (unless (uiop:directory-exists-p dir)
      (btr-fail "REGISTER-ROS-PACKAGE: directory ~a of package ~s does not exist" dir name))
    (setf *ros-package-directories*
          (acons name dir (remove name *ros-package-directories* :key #'car :test #'string=)))
    (native:add-package-path name (namestring dir))
    dir))

(defun ros-package-directory (name)
  "The directory of the ROS package NAME: registered ones first, then ROS_PACKAGE_PATH and
/usr/share; an error naming the package when none is found."
  (or (cdr (assoc name *ros-package-directories* :test #'string=))
      (loop for root in (append (uiop:split-string (or (uiop:getenv "ROS_PACKAGE_PATH") "")
                                                    :separator ":")
                                '("/usr/share/"))
            for dir = (and (plusp (length root))
                           (uiop:directory-exists-p
                            (merge-pathnames (uiop:ensure-directory-pathname name)
                                             (uiop:ensure-directory-pathname root))))
            when dir return dir)
      ;; deeper in a workspace on ROS_PACKAGE_PATH, as rospack finds it (ROS-LOAD's crawl)
      (let ((crawl (find-symbol "ROS-PACKAGE-DIRECTORY" :ros-load-manifest)))
        (and crawl (fboundp crawl) (funcall crawl name)))
      (btr-fail "ROS package ~s not found: register it with BTR:REGISTER-ROS-PACKAGE or put it on ROS_PACKAGE_PATH" name)))

(defvar *file-truenames* (make-hash-table :test 'equal :synchronized t)
  "Native namestring of a file RESOLVE-URI found → (truename device inode). PROBE-FILE resolves
every directory of a path (a system call each); one stat of the path tells whether it still
names the same file, whose truename is then the one found before.")

(defun file-identity (native-name)
  "(device inode) of the file NATIVE-NAME names (symbolic links followed), or NIL."
  (multiple-value-bind (ok device inode) (sb-unix:unix-stat native-name)
    (and ok (list device inode))))

(defun probe-file-again (path)
  "PROBE-FILE of PATH, taken from *FILE-TRUENAMES* while PATH names the same file as then."
  (let* ((name (sb-ext:native-namestring path))
         (cached (gethash name *file-truenames*)))
    (if (and cached (equal (file-identity name) (cdr cached)))
        (car cached)
        (let ((truename (probe-file path))
              (identity (file-identity name)))
          (when (and truename identity)
            (setf (gethash name *file-truenames*) (cons truename identity)))
          truename))))

(defun resolve-uri (uri)
  "The local file of URI (package://PKG/path, file://path or a path); an error when missing."
  (let ((path (cond ((uiop:string-prefix-p "package://" uri)
                     (let* ((rest (subseq uri 10)) (slash (position #\/ rest)))
                       (unless slash (btr-fail "mesh URI ~s has no path after the package name" uri))
                       (merge-pathnames (subseq rest (1+ slash))
                                        (ros-package-directory (subseq rest 0 slash)))))
                    ((uiop:string-prefix-p "file://" uri) (pathname (subseq uri 7)))
                    (t (pathname uri)))))
    (or (probe-file-again path)
        (btr-fail "mesh file ~a (from ~s) does not exist" path uri))))

(defvar *mesh-files* '()
  "Alist of mesh keywords: (keyword uri-or-path flag), the flag being CRAM's flip-winding-order
(kept, not used). ADD-OBJECTS-TO-MESH-LIST fills it.")

(defparameter *all-meshes-as-compound* t
  "The default of the :COMPOUND key of :MESH objects (ADD-OBJECT), as in CRAM. True: the
collision shape of a movable mesh object is one convex hull per sub-mesh of its file (the
meshes of an OBJ or DAE file; an STL file has one), children of a compound shape, so the
hollows between the parts stay free; a static one (mass 0) is the exact triangle mesh. NIL: one
convex hull over every vertex of the file, movable or static (hollows filled).")

(defun file-name->keyword (name)
  "fork_plastic → :FORK-PLASTIC."
  (intern (string-upcase (substitute #\- #\_ name)) :keyword))

(defun add-objects-to-mesh-list (ros-package &key (directory "resource") (extension nil))
  "Add every mesh file (stl, dae, obj, or only EXTENSION) in DIRECTORY of ROS-PACKAGE to
*MESH-FILES* as keywords named after the files (fork_plastic.stl → :FORK-PLASTIC); existing
entries are replaced. Returns the keywords."
  (let* ((dir (merge-pathnames (uiop:ensure-directory-pathname directory)
                               (ros-package-directory ros-package)))
         (extensions (if extension (list (string-downcase extension)) '("stl" "dae" "obj")))
         (added '()))
    (unless (uiop:directory-exists-p dir)
      (btr-fail "ADD-OBJECTS-TO-MESH-LIST: ~a (directory ~s of package ~s) does not exist"
                dir directory ros-package))
    (dolist (file (sort (uiop:directory-files dir) #'string< :key #'namestring))
      (when (member (string-downcase (or (pathname-type file) "")) extensions :test #'string=)
        (let ((key (file-name->keyword (pathname-name file)))
              (uri (format nil "package://~a/~a/~a.~a" ros-package (string-right-trim "/" directory)
                           (pathname-name file) (pathname-type file))))
          (setf *mesh-files* (cons (list key uri nil) (remove key *mesh-files* :key #'first)))
          (push key added))))
    (nreverse added)))

(defun mesh-path (mesh)
  "The local file of MESH: a keyword of *MESH-FILES*, a URI string or a pathname."
  (cond ((keywordp mesh)
         (let ((entry (assoc mesh *mesh-files*)))
           (unless entry
             (btr-fail "mesh ~s is not in *MESH-FILES*; known meshes: ~{~s~^ ~} (see ADD-OBJECTS-TO-MESH-LIST)"
                       mesh (mapcar #'first *mesh-files*)))
           (resolve-uri (second entry))))
        ((stringp mesh) (resolve-uri mesh))
        ((pathnamep mesh) (resolve-uri (namestring mesh)))
        (t (btr-fail ":mesh ~s, expected a mesh keyword, a URI string or a pathname" mesh))))

(define-object-kind :mesh (world pose (mass 0) mesh (scale 1) (compound *all-meshes-as-compound*)
                               disable-face-culling)
  (declare (ignore disable-face-culling))
  (unless mesh (btr-fail ":mesh object needs :mesh (a keyword of *MESH-FILES* or a file)"))
  (unless (or (and (realp scale) (> scale 0))
              (and (listp scale) (= 3 (length scale)) (every (lambda (s) (and (realp s) (> s 0))) scale)))
    (btr-fail ":mesh scale ~s, expected a positive real or (sx sy sz)" scale))
  (values (native:add-mesh (world-handle world) pose (namestring (mesh-path mesh))
                           :mass (mass-arg mass ":mesh") :scale scale
                           :single-hull (not compound))
          'item (if (keywordp mesh) (list mesh) '(:mesh))))

(defun project-resources-directory ()
  "The resources/ directory of cram-plans (models, meshes, maps)."
  (asdf:system-relative-pathname "cram-plans/cram-bullet-reasoning" "resources/"))

(defun register-project-meshes ()
  "Register the ROS package cram_plans_resources (this project's resources/) and put its meshes
into *MESH-FILES* (:bottle, :mug, :cup, :bowl, :fork-plastic, :breakfast-cereal, :milk, ...)."
  (register-ros-package "cram_plans_resources" (project-resources-directory))
  (add-objects-to-mesh-list "cram_plans_resources" :directory "meshes"))

(register-project-meshes)
